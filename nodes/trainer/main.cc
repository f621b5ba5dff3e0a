/// @file main.cc
/// @brief p2i_trainer: the trainer node process (RunNode's exit codes; see trainer_node.h).
#include <cstdio>
#include <cstdlib>

#include "nodes/trainer/trainer_node.h"

int main(int argc, char** argv) {
  using p2i::runtime::NodeArgs;
  try {
    p2i::trainer::TrainerNode node(NodeArgs::Parse(argc, argv));
    node.Spin();
    if (!node.TrainingStopped()) {
      // model::Trainer cannot be interrupted: leave the round behind rather than wait for it.
      // Published versions are complete files; nothing else needs flushing.
      std::fflush(nullptr);
      std::_Exit(0);
    }
    return 0;
  } catch (const p2i::runtime::StartupError& e) {
    std::fprintf(stderr, "%s: start-up error: %s\n", argv[0], e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", argv[0], e.what());
    return 1;
  }
}
