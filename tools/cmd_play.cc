/// @file cmd_play.cc
/// @brief `p2i play FILE.mcap [--rate R] [--loop] [--topics ...] [--start S]`, like
/// `ros2 bag play`: republishes the recorded p2i topics with the recorded timing.
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "nodes/runtime/shutdown.h"
#include "recording/player.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunPlay(const std::vector<std::string>& args) {
  CLI::App app{"Republish an MCAP recording on its topics with the recorded timing", "p2i play"};
  recording::PlayerOptions o;
  app.add_option("file", o.input, "FILE.mcap")->required();
  app.add_option("-r,--rate", o.rate, "Speed factor (2 = twice as fast)");
  app.add_flag("-l,--loop", o.loop, "Start again at the end (until Ctrl-C)");
  app.add_option("--topics", o.topics, "Only these topics");
  app.add_option("--start", o.start_s, "Skip the first S seconds of the recording");
  app.add_option("--delay", o.delay_s, "s to wait for subscribers before the first message");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  for (auto& t : o.topics)
    if (!t.empty() && t[0] != '/') t = "/" + t;
  runtime::Shutdown::InstallSignalHandlers();
  try {
    recording::Player player(o);
    std::string error;
    if (!player.Run(&error)) {
      std::fprintf(stderr, "p2i play: %s\n", error.c_str());
      return 1;
    }
    const auto& s = player.Stats();
    std::fprintf(stderr, "p2i play: published %llu messages (%d pass%s), skipped %llu, unreadable %llu\n",
                 static_cast<unsigned long long>(s.published), s.loops, s.loops == 1 ? "" : "es",
                 static_cast<unsigned long long>(s.skipped),
                 static_cast<unsigned long long>(s.unreadable));
    if (!s.stop_reason.empty())
      std::fprintf(stderr, "p2i play: the recording ends early: %s\n", s.stop_reason.c_str());
  } catch (const std::invalid_argument& e) {  // a bad option value: usage/config (exit 2)
    std::fprintf(stderr, "p2i play: %s\n", e.what());
    return 2;
} catch (const std::exception& e) {
    std::fprintf(stderr, "p2i play: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

P2I_COMMAND("play", "Republish an MCAP recording: play FILE.mcap [--rate R] [--loop] [--topics ...] [--start S]",
            RunPlay);

}  // namespace p2i::tools
