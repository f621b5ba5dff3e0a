/// @file main.cc
/// @brief p2i_trainer: the trainer node process (RunNode's exit codes; see trainer_node.h).
/// SIGINT/SIGTERM stop a running training round at its next step boundary (checkpoint saved).
#include "nodes/runtime/node.h"
#include "nodes/trainer/trainer_node.h"

int main(int argc, char** argv) { return p2i::runtime::RunNode<p2i::trainer::TrainerNode>(argc, argv); }
