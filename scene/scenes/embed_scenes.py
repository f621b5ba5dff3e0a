# Regenerates scene/sim_builtin_scenes.cc from scene/scenes/*.yaml (run from the project root).
import sys
names = ["small_office", "large_office"]
out = ['/// @file sim_builtin_scenes.cc',
       '/// @brief GENERATED from scene/scenes/*.yaml: edit the YAML files, then regenerate this file',
       '/// (python3 scene/scenes/embed_scenes.py); tests/scene/sim_scene_test.cc checks both agree.',
       '#include "scene/sim_builtin_scenes.h"', '', '#include <map>', '#include <stdexcept>', '',
       'namespace p2i::scene {', 'namespace {', '',
       '// long-function: generated table of the scene files',
       'const std::map<std::string, std::string>& Scenes() {',
       '  static const auto* const kScenes = new std::map<std::string, std::string>{']
for n in names:
    text = open(f"scene/scenes/{n}.yaml").read()
    assert ")p2i_yaml\"" not in text
    out.append(f'      {{"{n}", R"p2i_yaml({text})p2i_yaml"}},')
out += ['  };', '  return *kScenes;', '}', '', '}  // namespace', '',
        'std::vector<std::string> BuiltInSceneNames() {', '  return {' + ", ".join(f'"{n}"' for n in names) + '};', '}', '',
        'const std::string& BuiltInSceneYaml(const std::string& name) {',
        '  const auto it = Scenes().find(name);',
        '  if (it == Scenes().end()) {',
        '    throw std::invalid_argument("unknown built-in scene \'" + name + "\' (known: ' + ", ".join(names) + ')");',
        '  }', '  return it->second;', '}', '', '}  // namespace p2i::scene', '']
open("scene/sim_builtin_scenes.cc", "w").write("\n".join(out))
