/// @file fusion_methods.h
/// @brief The registry entry of `open3d_tsdf` (model/method_registry.cc lists it) and the option
/// keys it shares with `fusion` (whose entry, with the learned refinement, is
/// refine/fusion_method.h).
#pragma once

#include <string>

#include "model/method_registry.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::fusion {

/// The option keys of both methods (FusionOptions::FromYaml): tsdf, blend, fill_holes.
const std::vector<std::string>& FusionOptionKeys();

/// Read {tsdf: {...}, blend: {...}, fill_holes: bool} (null = defaults, fill_holes on), check
/// them once (bad keys or values throw std::runtime_error naming `source`, the line and the key)
/// and return a factory building `open3d_tsdf` (Open3D's voxel-colour raycast of the TSDF) over
/// MethodInputs::training, all frames integrated.
model::MethodFactory ConfigureOpen3dTsdf(const YAML::Node& options, const std::string& source);

}  // namespace p2i::fusion
