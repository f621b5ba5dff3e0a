/// @file sim_builtin_scenes.h
/// @brief The scene YAML files of scene/scenes/, embedded in the binary so that the default
/// scene needs no file. A test checks that the embedded text equals the files.
#pragma once

#include <string>
#include <vector>

namespace p2i::scene {

/// Names of the embedded scenes ("small_office", "large_office").
std::vector<std::string> BuiltInSceneNames();
/// The embedded YAML text of scene `name`. Throws std::invalid_argument naming the known scenes.
const std::string& BuiltInSceneYaml(const std::string& name);

}  // namespace p2i::scene
