/// @file launch_substitution.h
/// @brief `$(var NAME)`, `$(dirname)`, `$(filename)` and `$(env NAME [DEFAULT])` in launch files.
#pragma once

#include <map>
#include <string>

namespace p2i::tools {

/// What substitutions can see while one launch file is read: its launch variables (command-line
/// overrides, `arg` values, `let`, include arguments) and the file's own path. A value type;
/// thread-compatible.
struct SubstitutionScope {
  std::map<std::string, std::string> vars;
  std::string file;  ///< absolute path of the launch file being read
};

/// Replaces every `$(...)` in `text`. Supported: `$(var NAME)`, `$(dirname)` (the launch file's
/// folder), `$(filename)` (its path), `$(env NAME)` / `$(env NAME DEFAULT)`. Substitutions do
/// not nest. Throws std::invalid_argument naming the substitution (and the variables that exist
/// for an unknown `var`); the caller adds file and line.
std::string Substitute(const std::string& text, const SubstitutionScope& scope);

}  // namespace p2i::tools
