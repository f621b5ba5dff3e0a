/// @file procedural_dataset.h
/// @brief An analytic textured room for tests and `p2i train --data procedural` (no external
/// renderer or dataset needed). Torch-free.
#pragma once

#include <cstdint>

#include "scene/rgbd_sample.h"

namespace p2i::model {

/// A procedural RGB-D scene: a textured room seen from poses along a smooth loop, rendered
/// analytically at `size` x `size`.
scene::RgbdDataset MakeProceduralDataset(int num_frames, int size, uint64_t seed = 0);

}  // namespace p2i::model
