/// @file main.cc
/// @brief p2i_pool: see pool_node.h.
#include "nodes/pool/pool_node.h"

int main(int argc, char** argv) { return p2i::runtime::RunNode<p2i::nodes::PoolNode>(argc, argv); }
