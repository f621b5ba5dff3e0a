/// @file recording_bench.cc
/// @brief Figures for issue 13 (docs/RECORDING.md):
///  1. `p2i record` (a child process pinned to one core) of 640x480 RGB-D at 30 Hz plus
///     synthetic views (128x128 at 10 Hz): messages lost, file size per minute, recorder CPU;
///  2. playback timing error p50/p99 at 1x (Player, scheduled vs actual publish time);
///  3. p2i_foxglove_bridge: added latency (bridge client receive - publish, minus a direct
///     ZeroMQ subscriber's) and throughput for 1 and 4 clients.
/// Writes recording_bench.json. Sim frames (built-in small_office) give realistic compression.
///   recording_bench [--seconds 20] [--bridge-seconds 8] [--out DIR] [--compression zstd]
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/bench_process.h"
#include "msgs/codec.h"
#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/node.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/shutdown.h"
#include "recording/mcap_reader.h"
#include "recording/player.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/foxglove_bridge/raw_ws_client.h"
#include "util/heap_policy.h"

using namespace p2i;
using Clock = std::chrono::steady_clock;

namespace {

std::string g_bin;

using bench::Child;
using bench::ChildOptions;

double Pct(const std::vector<double>& v, double p) { return bench::Percentile(v, 100.0 * p); }

struct Frames {
  std::vector<msgs::RgbdFrame> rgbd;
  std::vector<msgs::View> views;
};

Frames MakeFrames(int n) {
  Frames f;
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  const auto cam = scene::SimScene::DefaultCamera(640, 480);
  const auto small = scene::SimScene::DefaultCamera(128, 128);
  const auto poses = scene::GenerateArmSweep(scene::ArmSweepOptions());
  for (int i = 0; i < n; ++i) {
    const auto& p = poses[(i * poses.size()) / n];
    const auto s = sim.Render(p.pose, cam, p.stamp);
    msgs::RgbdFrame m;
    msgs::MutableHeader(m)->set_frame_id("camera");
    convert::ToMsg(cam, m.meta.mutable_camera_info());
    convert::ToMsg(p.pose, m.meta.mutable_pose());
    m.rgb = convert::ToImage(s.rgb);
    m.depth = convert::ToImage(s.depth);
    f.rgbd.push_back(m);
    const auto v = sim.Render(p.pose, small, p.stamp);
    msgs::View view;
    convert::ToMsg(p.pose, view.meta.mutable_pose());
    view.meta.set_method("sim");
    view.rgb = convert::ToImage(v.rgb);
    view.depth = convert::ToImage(v.depth);
    f.views.push_back(view);
  }
  return f;
}

/// The publishers live in a node of their own, gone before BenchPlay republishes the same
/// topics (their ipc endpoints would still be bound: "endpoint already bound").
nlohmann::json BenchRecord(const Frames& frames, double seconds, const std::string& out,
                           const std::string& compression) {
  runtime::Node node("recording_bench_pub",
                     runtime::NodeArgs::Parse(std::vector<std::string>{"status_period:=0"}));
  auto rgbd_pub = node.Advertise<msgs::RgbdFrame>("/bench/rgbd");
  auto view_pub = node.Advertise<msgs::View>("/bench/views");
  const std::string file = out + "/bench.mcap";
  std::filesystem::remove(file);
  Child rec({g_bin + "/p2i", "record", "/bench/rgbd", "/bench/views", "-o", file,
             "--compression", compression},
            ChildOptions{"", out + "/record.log", 0});
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // connect (slow joiner)
  uint64_t rgbd_sent = 0, views_sent = 0;
  const auto start = Clock::now();
  auto next = start;
  int tick = 0;
  while (Clock::now() - start < std::chrono::duration<double>(seconds)) {
    std::this_thread::sleep_until(next);
    next += std::chrono::microseconds(33333);
    rgbd_pub->Publish(frames.rgbd[tick % frames.rgbd.size()]);
    ++rgbd_sent;
    if (tick % 3 == 0) {
      view_pub->Publish(frames.views[tick % frames.views.size()]);
      ++views_sent;
    }
    ++tick;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  double cpu = 0;
  rec.Stop(SIGINT, &cpu);
  recording::McapReader r;
  std::string error;
  nlohmann::json j;
  if (!r.Open(file, &error)) {
    std::fprintf(stderr, "recording_bench: %s\n", error.c_str());
    return j;
  }
  const auto& s = r.Summary();
  uint64_t rgbd_got = 0, views_got = 0;
  for (const auto& [id, ch] : s.channels) {
    const uint64_t n = s.stats.channel_message_counts.count(id) ? s.stats.channel_message_counts.at(id) : 0;
    (ch.topic == "/bench/rgbd" ? rgbd_got : views_got) += n;
  }
  const double dur = (s.stats.message_end_time - s.stats.message_start_time) / 1e9;
  const double raw_per_frame = static_cast<double>(msgs::WireSize(msgs::Encode(frames.rgbd[0])));
  j = {{"seconds", seconds},
       {"compression", compression},
       {"rgbd_published", rgbd_sent},
       {"rgbd_recorded", rgbd_got},
       {"views_published", views_sent},
       {"views_recorded", views_got},
       {"lost", (rgbd_sent - rgbd_got) + (views_sent - views_got)},
       {"file_bytes", s.file_size},
       {"mib_per_minute", s.file_size / (1 << 20) / std::max(dur, 1e-9) * 60.0},
       {"raw_mib_per_minute", raw_per_frame * 30 * 60 / (1 << 20)},
       {"recorder_cpu_s", cpu},
       {"recorder_core_fraction", cpu / (seconds + 2.0)},
       {"file", file}};
  std::printf("record (p2i record pinned to cpu 0, %s): %llu/%llu RGB-D 640x480 + %llu/%llu views "
              "128x128 recorded (lost %llu); %.0f MiB/min (raw %.0f MiB/min); recorder CPU %.2f s "
              "for %.0f s = %.0f%% of one core\n",
              compression.c_str(), (unsigned long long)rgbd_got, (unsigned long long)rgbd_sent,
              (unsigned long long)views_got, (unsigned long long)views_sent,
              (unsigned long long)j["lost"].get<uint64_t>(), j["mib_per_minute"].get<double>(),
              j["raw_mib_per_minute"].get<double>(), cpu, seconds + 2.0,
              100.0 * j["recorder_core_fraction"].get<double>());
  return j;
}

nlohmann::json BenchPlay(const std::string& file) {
  recording::PlayerOptions o;
  o.input = file;
  o.delay_s = 0.2;
  o.node_name = "/bench_play";
  recording::Player player(o);
  std::vector<double> err_ms;
  std::string error;
  player.Run(&error, [&](const std::string&, int64_t scheduled, int64_t actual) {
    err_ms.push_back((actual - scheduled) / 1e6);
  });
  nlohmann::json j = {{"messages", err_ms.size()},
                      {"p50_ms", Pct(err_ms, 0.5)},
                      {"p99_ms", Pct(err_ms, 0.99)},
                      {"max_ms", Pct(err_ms, 1.0)}};
  std::printf("play 1x: %zu messages, timing error (actual - recorded schedule) p50 %.3f ms, "
              "p99 %.3f ms, max %.3f ms\n",
              err_ms.size(), Pct(err_ms, 0.5), Pct(err_ms, 0.99), Pct(err_ms, 1.0));
  return j;
}

// The port the bridge wrote to port_file (0 if none within 10 s).
int WaitForPort(const std::string& port_file) {
  int port = 0;
  for (int i = 0; i < 200 && port == 0; ++i) {
    std::ifstream in(port_file);
    in >> port;
    if (port == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return port;
}

// One Foxglove client: subscribes to /bench/live, then records each message's publish-to-
// receive latency and size until `stop`.
void BridgeClient(int port, const std::atomic<bool>& stop, std::atomic<int>* subscribed,
                  std::vector<double>* lat, uint64_t* bytes) {
  testing::RawWs ws(port);
  if (!ws.ok() || ws.Handshake("foxglove.websocket.v1").find(" 101 ") == std::string::npos) return;
  uint32_t channel = 0;
  ws.WaitText([&](const nlohmann::json& j) {
    if (j["op"] != "advertise") return false;
    for (const auto& ch : j["channels"])
      if (ch["topic"] == "/bench/live") channel = ch["id"];
    return channel != 0;
  });
  ws.SendFrame(1, nlohmann::json{{"op", "subscribe"},
                                 {"subscriptions", {{{"id", 1}, {"channelId", channel}}}}}
                      .dump());
  ++*subscribed;
  uint8_t op;
  std::string p;
  while (!stop) {
    if (!ws.ReadFrame(&op, &p, 200) || op != 2 || p.size() < 13) continue;
    const int64_t now = runtime::NowNs();
    msgs::pb::HeaderOnly ho;  // the recorded message starts with the header frame
    if (ho.ParsePartialFromArray(p.data() + 13, static_cast<int>(p.size() - 13)))
      lat->push_back((now - ho.header().publish_stamp_ns()) / 1e6);
    *bytes += p.size();
  }
}

// The frames at 30 Hz for `seconds`; returns how many were published.
uint64_t PublishAt30Hz(const Frames& frames, double seconds,
                       const std::shared_ptr<runtime::Publisher<msgs::RgbdFrame>>& pub) {
  const auto start = Clock::now();
  auto next = start;
  uint64_t sent = 0;
  int tick = 0;
  while (Clock::now() - start < std::chrono::duration<double>(seconds)) {
    std::this_thread::sleep_until(next);
    next += std::chrono::microseconds(33333);
    pub->Publish(frames.rgbd[tick++ % frames.rgbd.size()]);
    ++sent;
  }
  return sent;
}

// The bridge's figures against the direct ZeroMQ baseline, printed and as JSON.
nlohmann::json BridgeSummary(int clients, double seconds, uint64_t sent,
                             const std::vector<std::vector<double>>& lat,
                             const std::vector<uint64_t>& bytes,
                             const std::vector<double>& direct_ms) {
  std::vector<double> all;
  uint64_t total_bytes = 0, received = 0;
  for (int c = 0; c < clients; ++c) {
    all.insert(all.end(), lat[c].begin(), lat[c].end());
    total_bytes += bytes[c];
    received += lat[c].size();
  }
  const double d50 = Pct(direct_ms, 0.5), d99 = Pct(direct_ms, 0.99);
  nlohmann::json j = {{"clients", clients},
                      {"published", sent},
                      {"received_per_client", static_cast<double>(received) / clients},
                      {"latency_p50_ms", Pct(all, 0.5)},
                      {"latency_p99_ms", Pct(all, 0.99)},
                      {"direct_zmq_p50_ms", d50},
                      {"direct_zmq_p99_ms", d99},
                      {"added_p50_ms", Pct(all, 0.5) - d50},
                      {"throughput_mib_s_total", total_bytes / (1 << 20) / seconds},
                      {"messages_per_s_per_client", received / seconds / clients}};
  std::printf("bridge, %d client(s): %llu sent, %.1f received per client; publish->client p50 %.2f "
              "ms p99 %.2f ms (direct ZeroMQ p50 %.2f ms p99 %.2f ms: added p50 %.2f ms); "
              "%.1f MiB/s total, %.1f msg/s per client\n",
              clients, (unsigned long long)sent, j["received_per_client"].get<double>(),
              Pct(all, 0.5), Pct(all, 0.99), d50, d99, Pct(all, 0.5) - d50,
              j["throughput_mib_s_total"].get<double>(), j["messages_per_s_per_client"].get<double>());
  return j;
}

nlohmann::json BenchBridge(const Frames& frames, int clients, double seconds,
                           const std::string& out,
                           std::shared_ptr<runtime::Publisher<msgs::RgbdFrame>> pub) {
  const std::string port_file = out + "/bridge.port";
  std::filesystem::remove(port_file);
  Child bridge({g_bin + "/p2i_foxglove_bridge", "port:=0", "port_file:=" + port_file,
                "foxglove:=false", "topics:=[/bench/live]", "max_queue_mb:=64"},
               ChildOptions{"", out + "/bridge.log", -1});
  const int port = WaitForPort(port_file);
  std::atomic<bool> stop{false};
  std::vector<std::vector<double>> lat(clients);
  std::vector<uint64_t> bytes(clients, 0);
  std::vector<std::thread> threads;
  std::atomic<int> subscribed{0};
  for (int c = 0; c < clients; ++c)
    threads.emplace_back(BridgeClient, port, std::cref(stop), &subscribed, &lat[c], &bytes[c]);
  // A direct ZeroMQ subscriber of the same topic (the baseline the bridge adds to).
  runtime::SubscriberOptions so;
  so.endpoints = {runtime::DefaultEndpoint("topic", "/bench/live")};
  runtime::RawSubscriber direct("/bench/live", so);
  std::vector<double> direct_ms;
  // Received on a thread of its own as soon as it arrives (polling it from the publishing loop
  // once per tick measured the tick, ~33 ms, not the transport).
  std::thread direct_thread([&] {
    msgs::WireMessage m;
    msgs::pb::Header h;
    while (!stop) {
      if (direct.Receive(&m, &h, std::chrono::milliseconds(200)))
        direct_ms.push_back((runtime::NowNs() - h.publish_stamp_ns()) / 1e6);
    }
  });
  const auto wait_until = Clock::now() + std::chrono::seconds(10);
  while (subscribed < clients && Clock::now() < wait_until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const uint64_t sent = PublishAt30Hz(frames, seconds, pub);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  stop = true;
  for (auto& t : threads) t.join();
  direct_thread.join();
  bridge.Stop();
  return BridgeSummary(clients, seconds, sent, lat, bytes, direct_ms);
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("recording_bench")) return 2;  // P2I_HEAP
  double seconds = 20, bridge_seconds = 8;
  std::string out = "recording_bench_out", compression = "zstd";
  for (int i = 1; i < argc; i += 2) {
    std::string k = argv[i];
    if (i + 1 == argc) k = "";  // every option takes a value: a lone flag (--help) is usage
    if (k == "--seconds") seconds = std::stod(argv[i + 1]);
    else if (k == "--bridge-seconds") bridge_seconds = std::stod(argv[i + 1]);
    else if (k == "--out") out = argv[i + 1];
    else if (k == "--compression") compression = argv[i + 1];
    else {
      std::fprintf(stderr, "usage: recording_bench [--seconds S] [--bridge-seconds S] [--out DIR] [--compression zstd|lz4|none]\n");
      return 2;
    }
  }
  g_bin = std::filesystem::canonical("/proc/self/exe").parent_path().string();
  if (std::thread::hardware_concurrency() > 1) {  // the recorder gets cpu 0, the publisher cpu 1
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(1, &set);
    sched_setaffinity(0, sizeof set, &set);
  }
  std::filesystem::create_directories(out);
  char run[] = "/tmp/p2i-rec-bench-XXXXXX";
  setenv("P2I_RUN_DIR", mkdtemp(run), 1);
  std::printf("rendering sim frames...\n");
  const Frames frames = MakeFrames(30);
  runtime::Node node("recording_bench", runtime::NodeArgs::Parse(std::vector<std::string>{"status_period:=0"}));
  nlohmann::json j;
  j["record"] = BenchRecord(frames, seconds, out, compression);
  if (j["record"].contains("file")) j["play"] = BenchPlay(j["record"]["file"]);
  auto live = node.Advertise<msgs::RgbdFrame>("/bench/live");
  j["bridge"] = nlohmann::json::array();
  for (int clients : {1, 4}) j["bridge"].push_back(BenchBridge(frames, clients, bridge_seconds, out, live));
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);
  j["loadavg"] = {load[0], load[1], load[2]};
  j["cpus"] = std::thread::hardware_concurrency();
  std::printf("load average %.2f %.2f %.2f on %u CPUs (shared machine)\n", load[0], load[1],
              load[2], std::thread::hardware_concurrency());
  std::ofstream(out + "/recording_bench.json") << j.dump(2) << "\n";
  // The same figures as one CSV (section, clients, metric, value) and a table.
  std::ofstream csv(out + "/recording_bench.csv");
  csv << "section,clients,metric,value\n";
  std::printf("\n| section | clients | metric | value |\n|---|---|---|---|\n");
  auto rows = [&](const std::string& section, const nlohmann::json& o) {
    const std::string clients = o.contains("clients") ? o["clients"].dump() : "";
    for (const auto& [k, v] : o.items()) {
      if (!v.is_number() || k == "clients") continue;
      csv << section << "," << clients << "," << k << "," << v.dump() << "\n";
      std::printf("| %s | %s | %s | %s |\n", section.c_str(), clients.c_str(), k.c_str(),
                  v.dump().c_str());
    }
  };
  rows("record", j["record"]);
  if (j.contains("play")) rows("play", j["play"]);
  for (const auto& b : j["bridge"]) rows("bridge", b);
  std::filesystem::remove_all(getenv("P2I_RUN_DIR"));
  return 0;
}
