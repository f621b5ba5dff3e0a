/// @file cmd_topic.cc
/// @brief `p2i topic list | info | echo | hz | delay | bw TOPIC | pub TOPIC TYPE VALUE`, like
/// `ros2 topic`.
///
/// Discovery: every publisher that binds writes $P2I_RUN_DIR/registry/<pid>.topic.<name>
/// (name, type, actual endpoint, node) and removes it when it closes; entries of dead processes
/// are ignored and cleaned up. `echo`/`hz` find a topic's endpoint there, else use the default
/// ipc endpoint derived from the name, or --endpoint.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "convert/depth.h"
#include "convert/image.h"
#include "msgs/codec.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/graph_discovery.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/rate_window.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/shutdown.h"
#include "tools/cli_exit.h"
#include "tools/command.h"
#include "tools/graph_json.h"

namespace p2i::tools {
namespace {

using runtime::Registry;
using runtime::RegistryEntry;

std::string Absolute(const std::string& topic) {
  return topic.empty() || topic[0] == '/' ? topic : "/" + topic;
}

/// Where to look: $P2I_RUN_DIR when set, else every running launch of this user (as
/// `ros2 topic list` needs nothing exported); plus the peers (--peer, else $P2I_PEERS).
struct Graph {
  std::vector<std::string> peers;
  std::vector<RegistryEntry> Entries() const {
    std::vector<std::string> errors;
    auto entries = runtime::DiscoverGraph(peers, std::chrono::milliseconds(1000), &errors);
    for (const auto& e : errors) std::fprintf(stderr, "p2i topic: warning: %s\n", e.c_str());
    return entries;
  }
};

/// Endpoints of all live publishers of `topic` here and on the peers (several nodes may
/// publish one topic on different endpoints), or the default one.
std::vector<std::string> FindEndpoints(const Graph& graph, const std::string& topic) {
  std::vector<std::string> out = runtime::ReachableEndpoints(graph.Entries(), "topic", topic);
  if (out.empty()) out.push_back(runtime::DefaultEndpoint("topic", topic));
  return out;
}

int List(const Graph& graph, bool show_types, bool verbose) {
  auto entries = graph.Entries();
  std::sort(entries.begin(), entries.end(), [](const RegistryEntry& a, const RegistryEntry& b) {
    return std::tie(a.kind, a.name, a.node, a.host) < std::tie(b.kind, b.name, b.node, b.host);
  });
  std::vector<std::string> printed;
  for (const auto& e : entries) {
    if (e.kind != "topic" && !verbose) continue;
    if (verbose) {
      std::printf("%-8s %-40s [%s] %s (node %s, pid %d%s%s)\n", e.kind.c_str(), e.name.c_str(),
                  e.type.c_str(), e.endpoint.c_str(), e.node.c_str(), e.pid,
                  e.host.empty() ? "" : ", via ", e.host.c_str());
      continue;
    }
    const std::string line = show_types ? e.name + " [" + e.type + "]" : e.name;
    if (std::find(printed.begin(), printed.end(), line) != printed.end()) continue;
    printed.push_back(line);
    std::printf("%s\n", line.c_str());
  }
  if (entries.empty()) {
    std::fprintf(stderr,
                 "p2i topic list: no running graph in %s (start one with `p2i launch`, or "
                 "export the P2I_RUN_DIR that `p2i launch` prints)\n",
                 runtime::RunDir().c_str());
  }
  return 0;
}

int Info(const Graph& graph, const std::string& topic) {
  std::string type;
  std::vector<runtime::RegistryEntry> pubs;
  for (const auto& e : graph.Entries()) {
    if (e.kind == "topic" && e.name == topic) {
      pubs.push_back(e);
      type = e.type;
    }
  }
  if (pubs.empty()) {
    std::fprintf(stderr, "p2i topic info: no publisher of %s in %s (p2i topic list shows the "
                         "topics)\n", topic.c_str(), runtime::RunDir().c_str());
    return 1;
  }
  std::printf("Type: %s\nPublisher count: %zu\n", type.c_str(), pubs.size());
  for (const auto& e : pubs)
    std::printf("  %s (pid %d) at %s%s%s\n", e.node.c_str(), e.pid, e.endpoint.c_str(),
                e.host.empty() ? "" : ", via ", e.host.c_str());
  std::printf("Subscription count: not known (subscribers connect without registering)\n");
  return 0;
}

// Writes the images of a View or RgbdFrame as PNG (depth as 16-bit millimetres).
void SaveImages(const msgs::WireMessage& m, const std::string& dir, int index) {
  std::vector<msgs::Image> images;
  std::string error;
  msgs::View view;
  msgs::RgbdFrame frame;
  if (msgs::Decode(m, &view, &error)) {
    images = {view.rgb, view.depth};
  } else if (msgs::Decode(m, &frame, &error)) {
    images = {frame.rgb, frame.depth};
  } else {
    return;  // no images in this message type
  }
  std::filesystem::create_directories(dir);
  const char* names[2] = {"rgb", "depth"};
  for (size_t i = 0; i < images.size(); ++i) {
    if (!images[i].data) continue;
    cv::Mat out;
    if (images[i].encoding == msgs::pb::RGB8) {
      cv::cvtColor(convert::RgbToMat(images[i]), out, cv::COLOR_RGB2BGR);
    } else if (images[i].encoding == msgs::pb::DEPTH16U ||
               images[i].encoding == msgs::pb::DEPTH32F) {
      convert::DepthToMetres(images[i]).convertTo(out, CV_16UC1, 1000.0);  // metres -> mm
    } else {
      out = convert::ToMat(images[i]);
    }
    char name[64];
    std::snprintf(name, sizeof(name), "%06d_%s.png", index, names[i]);
    const std::string path = (std::filesystem::path(dir) / name).string();
    if (!cv::imwrite(path, out)) throw std::runtime_error("cannot write " + path);
    std::fprintf(stderr, "saved %s\n", path.c_str());
  }
}

int Pub(const std::string& topic, const std::string& type, const std::string& value,
        double rate_hz, int times, const std::string& endpoint) {
  const msgs::pb::MsgType t = MsgTypeFromName(type);
  const std::string me = "/p2i_topic_pub_" + std::to_string(::getpid());
  auto msg = MessageFromText(t, value, me);
  runtime::PublisherOptions o;
  o.endpoint = endpoint;
  runtime::RawPublisher pub(topic, type, me, o);
  std::printf("publisher: beginning loop on %s (%s)\n", topic.c_str(), pub.Endpoint().c_str());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // let subscribers connect
  for (int i = 1; (times <= 0 || i <= times) && !runtime::Shutdown::Requested(); ++i) {
    StampHeader(msg.get(), pub.NextSeq(), 0);
    msgs::WireMessage w;
    w.header = msg->SerializeAsString();
    pub.Publish(w);
    std::printf("publishing #%d: %s\n", i, msg->ShortDebugString().c_str());
    std::fflush(stdout);
    if (times > 0 && i == times) break;
    runtime::Shutdown::WaitFor(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate_hz)));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the last one leave
  return 0;
}

std::vector<std::string> g_peers;  // --peer / $P2I_PEERS, set by RunTopic

runtime::SubscriberOptions SubOptions(const std::string& topic,
                                      const std::vector<std::string>& endpoints) {
  runtime::SubscriberOptions o;
  o.endpoints = endpoints.empty() ? FindEndpoints(Graph{g_peers}, topic) : endpoints;
  return o;
}

int Echo(const std::string& topic, const std::vector<std::string>& endpoints, int count,
         double timeout_s, const std::string& save_dir) {
  runtime::RawSubscriber sub(topic, SubOptions(topic, endpoints));
  int shown = 0;
  // --timeout counts from the last message (or the start): a stream that stops is noticed too.
  auto last = std::chrono::steady_clock::now();
  while (!runtime::Shutdown::Requested() && (count <= 0 || shown < count)) {
    msgs::WireMessage m;
    msgs::pb::Header h;
    if (!sub.Receive(&m, &h, std::chrono::milliseconds(200))) {
      if (timeout_s > 0 && std::chrono::steady_clock::now() - last >
                               std::chrono::duration<double>(timeout_s)) {
        std::fprintf(stderr, "p2i topic echo: no message on %s for %.1f s%s\n", topic.c_str(),
                     timeout_s, shown > 0 ? " (since the last one)" : "");
        return 1;
      }
      continue;
    }
    last = std::chrono::steady_clock::now();
    std::string text = msgs::DebugString(m);  // images as "<blob N: W x H ENC, B bytes>"
    while (!text.empty() && text.back() == '\n') text.pop_back();
    std::printf("%s\n---\n", text.c_str());
    // SIGPIPE is ignored (Shutdown): a closed stdout (`| head`) ends the echo quietly.
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) return 0;
    if (!save_dir.empty()) SaveImages(m, save_dir, shown);
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

/// `delay` (receipt time minus the header's publish stamp; hosts must share a clock, as on one
/// machine or between network namespaces) and `bw` (bytes per second), like `ros2 topic
/// delay/bw`, printed once a second; a summary line at the end for scripts.
int DelayOrBw(bool delay, const std::string& topic, const std::vector<std::string>& endpoints,
              double duration_s) {
  runtime::RawSubscriber sub(topic, SubOptions(topic, endpoints));
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto next_report = start + std::chrono::seconds(1);
  std::vector<double> values;  // delay s, or message bytes
  std::vector<double> all;
  double first_t = -1, last_t = -1;
  while (!runtime::Shutdown::Requested()) {
    const auto now = Clock::now();
    if (duration_s > 0 && now - start >= std::chrono::duration<double>(duration_s)) break;
    msgs::WireMessage m;
    msgs::pb::Header h;
    if (sub.Receive(&m, &h, std::chrono::milliseconds(50))) {
      const double t = std::chrono::duration<double>(Clock::now() - start).count();
      if (first_t < 0) first_t = t;
      last_t = t;
      const double v = delay ? (runtime::NowNs() - static_cast<int64_t>(h.publish_stamp_ns())) * 1e-9
                             : static_cast<double>(msgs::WireSize(m));
      values.push_back(v);
      all.push_back(v);
    }
    if (Clock::now() < next_report) continue;
    next_report += std::chrono::seconds(1);
    if (values.empty()) {
      std::printf("no new messages\n");
    } else {
      double sum = 0, mn = values[0], mx = values[0];
      for (double v : values) sum += v, mn = std::min(mn, v), mx = std::max(mx, v);
      const double mean = sum / values.size();
      double var = 0;
      for (double v : values) var += (v - mean) * (v - mean);
      if (delay) {
        std::printf("average delay: %.3f ms\n\tmin: %.3f ms max: %.3f ms std dev: %.3f ms "
                    "window: %zu\n", mean * 1e3, mn * 1e3, mx * 1e3,
                    std::sqrt(var / values.size()) * 1e3, values.size());
      } else {
        std::printf("%.2f MB/s from %zu messages\n\tMessage size mean: %.2f MB min: %.2f MB "
                    "max: %.2f MB\n", sum / 1e6, values.size(), mean / 1e6, mn / 1e6, mx / 1e6);
      }
      values.clear();
    }
    std::fflush(stdout);
  }
  if (!all.empty()) {
    std::vector<double> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    double sum = 0;
    for (double v : all) sum += v;
    const double span = last_t - first_t;
    if (delay) {
      std::printf("summary: %zu messages, delay p50 %.3f ms p99 %.3f ms max %.3f ms\n",
                  all.size(), sorted[sorted.size() / 2] * 1e3,
                  sorted[std::min(sorted.size() - 1, sorted.size() * 99 / 100)] * 1e3,
                  sorted.back() * 1e3);
    } else {
      std::printf("summary: %zu messages, %.2f MB, %.2f MB/s, %.1f messages/s\n", all.size(),
                  sum / 1e6, span > 0 ? (sum - all.front()) / span / 1e6 : 0.0,
                  span > 0 ? (all.size() - 1) / span : 0.0);
    }
  }
  return all.empty() ? 1 : 0;
}

// long-function: one flat CLI11 table of the subcommands and their options, then the dispatch
int RunTopic(const std::vector<std::string>& args) {
  CLI::App app{"Inspect topics of running nodes (like `ros2 topic`). Topics are discovered "
               "from $P2I_RUN_DIR/registry, else from every running launch of this user, and "
               "from the registries of other hosts (--peer, $P2I_PEERS; docs/MULTIHOST.md).",
               "p2i topic"};
  app.require_subcommand(1);
  {
    const auto env = runtime::PeerRegistries();
    g_peers = env;
  }
  std::vector<std::string> peers;
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
  echo->add_option("--timeout", timeout_s, "Fail if no message arrives for S seconds, counted from the last message (0 = wait)");

  size_t window = 10000;
  double duration_s = 0;
  std::string save_dir;
  echo->add_option("--save-image", save_dir,
                   "Write the images of View / RgbdFrame messages to DIR as PNG "
                   "(NNNNNN_rgb.png, NNNNNN_depth.png: 16-bit mm)");
  auto* info = app.add_subcommand("info", "Print a topic's type and publishers");
  info->add_option("topic", topic, "Topic name (absolute, or relative to /)")->required();
  std::string type, value, pub_endpoint;
  double rate_hz = 1.0;
  int times = 0;
  bool pub_once = false;
  auto* pub = app.add_subcommand("pub", "Publish a message (YAML/JSON) on a topic");
  pub->add_option("topic", topic, "Topic name (absolute, or relative to /)")->required();
  pub->add_option("type", type, "Message type, e.g. PoseStamped, PoseRequest")->required();
  pub->add_option("value", value, "The message as YAML/JSON (fields of msgs/p2i.proto), e.g. "
                                  "'{pose: {position: {z: 1}, orientation: {w: 1}}}'");
  pub->add_option("-r,--rate", rate_hz, "Messages per second (default 1)")
      ->check(CLI::PositiveNumber);
  pub->add_option("-t,--times", times, "Publish N messages and exit (0 = until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  pub->add_flag("-1,--once", pub_once, "Publish one message and exit");
  pub->add_option("--endpoint", pub_endpoint, "Bind here instead of the default endpoint");
  auto* hz = app.add_subcommand("hz", "Print the publishing rate of a topic");
  hz->add_option("topic", topic, "Topic name (absolute, or relative to /)")->required();
  hz->add_option("-w,--window", window, "Number of periods in the statistics window");
  hz->add_option("--endpoint", endpoints, "Connect here instead of the discovered endpoint");
  hz->add_option("--duration", duration_s, "Stop after S seconds (0 = until Ctrl-C)");
  auto* delay = app.add_subcommand("delay", "Print the delay from publication to receipt");
  auto* bw = app.add_subcommand("bw", "Print the bandwidth used by a topic");
  for (auto* sub : {list, info, echo, hz, delay, bw}) {
    sub->add_option("--peer", peers,
                    "Registry of another host's launch, tcp://ADDRESS:PORT (repeatable; "
                    "default $P2I_PEERS)");
  }
  for (auto* sub : {delay, bw}) {
    sub->add_option("topic", topic, "Topic name (absolute, or relative to /)")->required();
    sub->add_option("--endpoint", endpoints, "Connect here instead of the discovered endpoint");
    sub->add_option("--duration", duration_s, "Stop after S seconds (0 = until Ctrl-C)");
  }

  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);  // CLI11 wants them reversed
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  runtime::Shutdown::InstallSignalHandlers();
  if (!peers.empty()) g_peers = peers;
  if (list->parsed()) return List(Graph{g_peers}, show_types, verbose);
  if (delay->parsed() || bw->parsed())
    return DelayOrBw(delay->parsed(), Absolute(topic), endpoints, duration_s);
  if (echo->parsed())
    return Echo(Absolute(topic), endpoints, once ? 1 : count, timeout_s, save_dir);
  if (info->parsed()) return Info(Graph{g_peers}, Absolute(topic));
  if (pub->parsed())
    return Pub(Absolute(topic), type, value, rate_hz, pub_once ? 1 : times, pub_endpoint);
  return Hz(Absolute(topic), endpoints, window, duration_s);
}

}  // namespace

P2I_COMMAND("topic", "Inspect topics: list | info | echo | hz | delay | bw TOPIC | pub TOPIC TYPE VALUE",
            RunTopic);

}  // namespace p2i::tools
