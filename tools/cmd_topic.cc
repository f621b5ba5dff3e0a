/// @file cmd_topic.cc
/// @brief `p2i topic list | echo TOPIC | hz TOPIC`, like `ros2 topic`.
///
/// Discovery: every publisher that binds writes $P2I_RUN_DIR/registry/<pid>.topic.<name>
/// (name, type, actual endpoint, node) and removes it when it closes; entries of dead processes
/// are ignored and cleaned up. `echo`/`hz` find a topic's endpoint there, else use the default
/// ipc endpoint derived from the name, or --endpoint.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "msgs/codec.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/rate_window.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/shutdown.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

using runtime::Registry;
using runtime::RegistryEntry;

std::string Absolute(const std::string& topic) {
  return topic.empty() || topic[0] == '/' ? topic : "/" + topic;
}

/// Endpoints of all live publishers of `topic` (several nodes may publish one topic on
/// different endpoints), or the default one.
std::vector<std::string> FindEndpoints(const std::string& topic) {
  std::vector<std::string> out;
  for (const auto& e : Registry::List()) {
    if (e.kind == "topic" && e.name == topic) out.push_back(e.endpoint);
  }
  if (out.empty()) out.push_back(runtime::DefaultEndpoint("topic", topic));
  return out;
}

int List(bool show_types, bool verbose) {
  const auto entries = Registry::List();
  std::vector<std::string> printed;
  for (const auto& e : entries) {
    if (e.kind != "topic" && !verbose) continue;
    if (verbose) {
      std::printf("%-8s %-40s [%s] %s (node %s, pid %d)\n", e.kind.c_str(), e.name.c_str(),
                  e.type.c_str(), e.endpoint.c_str(), e.node.c_str(), e.pid);
      continue;
    }
    const std::string line = show_types ? e.name + " [" + e.type + "]" : e.name;
    if (std::find(printed.begin(), printed.end(), line) != printed.end()) continue;
    printed.push_back(line);
    std::printf("%s\n", line.c_str());
  }
  return 0;
}

runtime::SubscriberOptions SubOptions(const std::string& topic,
                                      const std::vector<std::string>& endpoints) {
  runtime::SubscriberOptions o;
  o.endpoints = endpoints.empty() ? FindEndpoints(topic) : endpoints;
  return o;
}

int Echo(const std::string& topic, const std::vector<std::string>& endpoints, int count,
         double timeout_s) {
  runtime::RawSubscriber sub(topic, SubOptions(topic, endpoints));
  int shown = 0;
  const auto start = std::chrono::steady_clock::now();
  while (!runtime::Shutdown::Requested() && (count <= 0 || shown < count)) {
    msgs::WireMessage m;
    msgs::pb::Header h;
    if (!sub.Receive(&m, &h, std::chrono::milliseconds(200))) {
      if (timeout_s > 0 && std::chrono::steady_clock::now() - start >
                               std::chrono::duration<double>(timeout_s)) {
        std::fprintf(stderr, "p2i topic echo: no message on %s within %.1f s\n", topic.c_str(),
                     timeout_s);
        return 1;
      }
      continue;
    }
    std::string text = msgs::DebugString(m);
    while (!text.empty() && text.back() == '\n') text.pop_back();
    std::printf("%s\n---\n", text.c_str());
    std::fflush(stdout);
    ++shown;
  }
  if (sub.Stats().malformed.load() > 0) {
    std::fprintf(stderr, "p2i topic echo: %llu malformed message(s) dropped (%s)\n",
                 static_cast<unsigned long long>(sub.Stats().malformed.load()),
                 sub.LastError().c_str());
  }
  return 0;
}

int Hz(const std::string& topic, const std::vector<std::string>& endpoints, size_t window,
       double duration_s) {
  runtime::RawSubscriber sub(topic, SubOptions(topic, endpoints));
  using Clock = std::chrono::steady_clock;
  runtime::RateWindow rate(window);
  const auto start = Clock::now();
  auto next_report = start + std::chrono::seconds(1);
  bool any = false;
  while (!runtime::Shutdown::Requested()) {
    const auto now = Clock::now();
    if (duration_s > 0 && now - start >= std::chrono::duration<double>(duration_s)) break;
    msgs::WireMessage m;
    msgs::pb::Header h;
    if (sub.Receive(&m, &h, std::chrono::milliseconds(50))) {
      rate.Add(std::chrono::duration<double>(Clock::now() - start).count());
      any = true;
    }
    if (Clock::now() < next_report) continue;
    next_report += std::chrono::seconds(1);
    const auto s = rate.Summarize();
    if (s.periods == 0) {
      if (!any) std::printf("no new messages\n");
    } else {
      std::printf("average rate: %.3f\n\tmin: %.3fs max: %.3fs std dev: %.5fs window: %zu\n",
                  s.rate_hz, s.min_s, s.max_s, s.stddev_s, s.periods + 1);
      if (sub.Stats().dropped.load() > 0) {
        std::printf("\tdropped (sequence gaps): %llu\n",
                    static_cast<unsigned long long>(sub.Stats().dropped.load()));
      }
    }
    std::fflush(stdout);
  }
  return 0;
}

int RunTopic(const std::vector<std::string>& args) {
  CLI::App app{"Inspect topics of running nodes (like `ros2 topic`). Topics are discovered "
               "from $P2I_RUN_DIR/registry (see docs/RUNTIME.md).",
               "p2i topic"};
  app.require_subcommand(1);
  bool show_types = false, verbose = false;
  auto* list = app.add_subcommand("list", "List the topics of running nodes");
  list->add_flag("-t,--show-types", show_types, "Also print each topic's message type");
  list->add_flag("-v,--verbose", verbose,
                 "Print type, endpoint, node and pid of every topic and service");

  std::string topic;
  std::vector<std::string> endpoints;
  int count = 0;
  bool once = false;
  double timeout_s = 0;
  auto* echo = app.add_subcommand("echo", "Print the messages of a topic");
  echo->add_option("topic", topic, "Topic name (absolute, or relative to /)")->required();
  echo->add_flag("--once", once, "Print one message and exit");
  echo->add_option("-n,--count", count, "Print N messages and exit");
  echo->add_option("--endpoint", endpoints, "Connect here instead of the discovered endpoint");
  echo->add_option("--timeout", timeout_s, "Fail if nothing arrives within S seconds (0 = wait)");

  size_t window = 10000;
  double duration_s = 0;
  auto* hz = app.add_subcommand("hz", "Print the publishing rate of a topic");
  hz->add_option("topic", topic, "Topic name (absolute, or relative to /)")->required();
  hz->add_option("-w,--window", window, "Number of periods in the statistics window");
  hz->add_option("--endpoint", endpoints, "Connect here instead of the discovered endpoint");
  hz->add_option("--duration", duration_s, "Stop after S seconds (0 = until Ctrl-C)");

  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);  // CLI11 wants them reversed
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  runtime::Shutdown::InstallSignalHandlers();
  if (list->parsed()) return List(show_types, verbose);
  if (echo->parsed()) return Echo(Absolute(topic), endpoints, once ? 1 : count, timeout_s);
  return Hz(Absolute(topic), endpoints, window, duration_s);
}

}  // namespace

P2I_COMMAND("topic", "Inspect topics: list | echo TOPIC | hz TOPIC", RunTopic);

}  // namespace p2i::tools
