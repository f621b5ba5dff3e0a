// The `p2i` command: dispatches to the subcommands registered in tools/cmd_*.cc.
//
// Exit codes, one rule for `p2i` and the nodes (docs/RUNTIME.md): 0 success, 1 runtime error,
// 2 usage or configuration error (unknown command or option, a bad value, an unusable launch
// file or config: a std::invalid_argument or LaunchError from the command).
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "tools/command.h"
#include "tools/launch_error.h"
#include "util/heap_policy.h"

namespace {

void PrintUsage() {
  std::printf("usage: p2i <command> [args...]\n\ncommands:\n");
  for (const auto& [name, cmd] : p2i::tools::Commands()) {
    std::printf("  %-10s %s\n", name.c_str(), cmd.summary.c_str());
  }
  std::printf("\nRun 'p2i <command> --help' for a command's options.\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help") {
    PrintUsage();
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  if (!p2i::util::ApplyHeapPolicyOrReport("p2i " + name)) return 2;  // P2I_HEAP
  auto it = p2i::tools::Commands().find(name);
  if (it == p2i::tools::Commands().end()) {
    std::fprintf(stderr, "p2i: unknown command '%s'\n\n", name.c_str());
    PrintUsage();
    return 2;
  }
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    return it->second.run(args);
  } catch (const p2i::tools::LaunchError& e) {
    std::fprintf(stderr, "p2i %s: error: %s\n", name.c_str(), e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "p2i %s: error: %s\n", name.c_str(), e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "p2i %s: error: %s\n", name.c_str(), e.what());
    return 1;
  }
}
