/// @file cli_exit.h
/// @brief The exit code of a CLI11 parse error under p2i's one rule (docs/RUNTIME.md): 0 for
/// --help, 2 for every usage error (CLI11's own codes, 100-115, are not used).
#pragma once

#include <CLI/CLI.hpp>

namespace p2i::tools {

/// Prints what CLI11 prints for `e` (help text or the error) and returns 0 or 2.
inline int CliExit(const CLI::App& app, const CLI::ParseError& e) {
  return app.exit(e) == 0 ? 0 : 2;
}

}  // namespace p2i::tools
