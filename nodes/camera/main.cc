/// @file main.cc
/// @brief p2i_camera: see camera_node.h.
#include "nodes/camera/camera_node.h"

int main(int argc, char** argv) {
  return p2i::runtime::RunNode<p2i::nodes::CameraNode>(argc, argv);
}
