/// @file transport_bench.cc
/// @brief Transport benchmark: 640x480 RGB-D frames over PUB/SUB (ipc, tcp loopback) and small
/// service round trips (ipc, tcp). Prints a table and writes CSV or JSON.
///
/// usage: transport_bench [OUT.csv|OUT.json] [--frames N] [--calls N]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include <zmq.hpp>

#include "msgs/codec.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_service.h"
#include "nodes/runtime/raw_subscriber.h"
#include "util/heap_policy.h"
#include "util/order_stats.h"

namespace {

using namespace p2i;
using Clock = std::chrono::steady_clock;

struct Row {
  std::string test, transport;
  double target_hz = 0;
  int sent = 0, received = 0;
  uint64_t dropped = 0, malformed = 0;
  double rate = 0;  // frames/s received, or calls/s
  double p50_ms = 0, p99_ms = 0, max_ms = 0;
  double mb_per_s = 0;
};

/// q in [0, 1]; nearest rank (util/order_stats.h), 0 when there are no samples.
double Percentile(const std::vector<double>& v, double q) {
  return v.empty() ? 0.0 : util::PercentileNearestRank(v, q * 100.0);
}

msgs::RgbdFrame MakeFrame(int w, int h) {
  msgs::RgbdFrame f;
  f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, w, h);
  uint8_t* rgb = f.rgb.MutableData();
  for (size_t i = 0; i < f.rgb.data->size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7);
  f.depth = msgs::Image::Allocate(msgs::pb::DEPTH16U, w, h);
  f.depth.depth_scale = 0.001;
  f.depth.invalid_value = 0;
  uint8_t* depth = f.depth.MutableData();
  for (size_t i = 0; i < f.depth.data->size(); ++i) depth[i] = static_cast<uint8_t>(i * 3);
  f.meta.set_camera_info_id("bench_camera");
  return f;
}

// What the subscriber of PubSub measured.
struct Received {
  std::vector<double> latencies_ms;
  int received = 0;
  uint64_t dropped = 0, malformed = 0;
  Clock::time_point t_first, t_last;
};

// PubSub's subscriber thread: sets `ready` at the first message, measures the `frames` frames
// from seq `first_seq` on (earlier ones are warm-up), reports gaps and losses on stderr.
void ReceiveFrames(const std::string& transport, const std::string& topic,
                   const std::string& endpoint, int frames, std::atomic<bool>* ready,
                   const std::atomic<bool>& done, const std::atomic<uint64_t>& first_seq,
                   Received* out) {
  runtime::SubscriberOptions so;
  so.endpoints = {endpoint};
  runtime::RawSubscriber sub(topic, so);
  out->latencies_ms.reserve(frames);
  uint64_t measured_from = 0, expected_seq = 0;
  auto last_rx = Clock::now();
  while (true) {
    msgs::WireMessage m;
    msgs::pb::Header h;
    if (!sub.Receive(&m, &h, std::chrono::milliseconds(50))) {
      if (done && Clock::now() - last_rx > std::chrono::milliseconds(500)) break;
      continue;
    }
    last_rx = Clock::now();
    *ready = true;
    msgs::RgbdFrame f;
    std::string err;
    if (!msgs::Decode(m, &f, &err)) {
      ++out->malformed;
      continue;
    }
    const uint64_t fs = first_seq.load();
    if (fs == 0 || h.seq() < fs) continue;  // warm-up
    if (measured_from == 0) {
      measured_from = h.seq();
      out->t_first = last_rx;
    }
    out->t_last = last_rx;
    ++out->received;
    if (h.seq() != expected_seq && expected_seq != 0) {
      std::fprintf(stderr, "  [%s] gap: expected seq %llu, got %llu\n", transport.c_str(),
                   static_cast<unsigned long long>(expected_seq),
                   static_cast<unsigned long long>(h.seq()));
    }
    expected_seq = h.seq() + 1;
    out->latencies_ms.push_back((runtime::NowNs() - h.publish_stamp_ns()) * 1e-6);
    if (h.seq() == fs + frames - 1) break;
  }
  if (out->received < frames && expected_seq != 0 &&
      expected_seq <= first_seq.load() + frames - 1) {
    std::fprintf(stderr, "  [%s] stopped waiting at seq %llu of %llu\n", transport.c_str(),
                 static_cast<unsigned long long>(expected_seq),
                 static_cast<unsigned long long>(first_seq.load() + frames - 1));
  }
  if (measured_from > first_seq.load()) {
    std::fprintf(stderr, "  [%s] first measured frame lost: got %llu first, expected %llu\n",
                 transport.c_str(), static_cast<unsigned long long>(measured_from),
                 static_cast<unsigned long long>(first_seq.load()));
  }
  out->dropped = frames - out->received;
  out->malformed += sub.Stats().malformed.load();
}

Row PubSub(const std::string& transport, const std::string& endpoint, int frames,
           double target_hz) {
  const std::string topic = "/bench/rgbd";
  runtime::PublisherOptions po;
  po.endpoint = endpoint;
  auto raw = std::make_shared<runtime::RawPublisher>(topic, "RgbdFrame", "/bench", po);
  runtime::Publisher<msgs::RgbdFrame> pub(raw, "/bench");

  std::atomic<bool> sub_ready{false}, done{false};
  std::atomic<uint64_t> first_seq{0};
  Received rx;
  std::thread sub_thread(ReceiveFrames, std::cref(transport), std::cref(topic), raw->Endpoint(),
                         frames, &sub_ready, std::cref(done), std::cref(first_seq), &rx);

  msgs::RgbdFrame frame = MakeFrame(640, 480);
  // Warm up until the subscriber is connected (slow joiner), then measure.
  while (!sub_ready) {
    pub.Publish(frame);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  first_seq = raw->Stats().published.load() + 1;
  const auto t0 = Clock::now();
  for (int i = 0; i < frames; ++i) {
    if (target_hz > 0) {
      std::this_thread::sleep_until(t0 + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(i / target_hz)));
    }
    frame.meta.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
    pub.Publish(frame);
  }
  done = true;
  sub_thread.join();

  Row r;
  r.test = "pubsub_rgbd_640x480";
  r.transport = transport;
  r.target_hz = target_hz;
  r.sent = frames;
  r.received = rx.received;
  r.dropped = rx.dropped;
  r.malformed = rx.malformed;
  const double span = std::chrono::duration<double>(rx.t_last - rx.t_first).count();
  r.rate = rx.received > 1 && span > 0 ? (rx.received - 1) / span : 0;
  r.p50_ms = Percentile(rx.latencies_ms, 0.50);
  r.p99_ms = Percentile(rx.latencies_ms, 0.99);
  r.max_ms = Percentile(rx.latencies_ms, 1.0);
  r.mb_per_s = r.rate * (640 * 480 * 5) / 1e6;
  return r;
}

Row Service(const std::string& transport, const std::string& endpoint, int calls) {
  std::atomic<bool> stop{false};
  std::string bound;
  std::atomic<bool> ready{false};
  std::thread server_thread([&] {
    runtime::ServiceServerOptions so;
    so.endpoint = endpoint;
    runtime::RawServiceServer server(
        "/bench/echo", "Echo", "/bench", so,
        [](const msgs::WireMessage& req, uint64_t, msgs::WireMessage* rep, std::string*) {
          rep->header = req.header;
          return true;
        });
    bound = server.Endpoint();
    ready = true;
    while (!stop) {
      zmq::pollitem_t item{server.Socket().handle(), 0, ZMQ_POLLIN, 0};
      zmq::poll(&item, 1, std::chrono::milliseconds(20));
      server.Drain();
    }
  });
  while (!ready) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  runtime::ServiceClientOptions co;
  co.endpoint = bound;
  runtime::RawServiceClient client("/bench/echo", co);
  msgs::WireMessage req, rep;
  req.header.assign(96, 'x');  // a small request (a pose request is ~90 bytes)
  std::string err;
  for (int i = 0; i < 100; ++i) client.Call(req, &rep, &err);  // warm-up
  std::vector<double> rtt;
  rtt.reserve(calls);
  int ok = 0;
  const auto t0 = Clock::now();
  for (int i = 0; i < calls; ++i) {
    const auto a = Clock::now();
    if (client.Call(req, &rep, &err)) ++ok;
    rtt.push_back(std::chrono::duration<double, std::milli>(Clock::now() - a).count());
  }
  const double span = std::chrono::duration<double>(Clock::now() - t0).count();
  stop = true;
  server_thread.join();
  Row r;
  r.test = "service_small_rtt";
  r.transport = transport;
  r.sent = calls;
  r.received = ok;
  r.dropped = calls - ok;
  r.rate = calls / span;
  r.p50_ms = Percentile(rtt, 0.50);
  r.p99_ms = Percentile(rtt, 0.99);
  r.max_ms = Percentile(rtt, 1.0);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("transport_bench")) return 2;  // P2I_HEAP
  std::string out_path;
  int frames = 1000, calls = 5000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc) frames = std::atoi(argv[++i]);
    else if (a == "--calls" && i + 1 < argc) calls = std::atoi(argv[++i]);
    else if (a == "-h" || a == "--help") {
      std::printf("usage: %s [OUT.csv|OUT.json] [--frames N] [--calls N]\n", argv[0]);
      return 0;
    } else out_path = a;
  }
  const std::string run_dir = runtime::RunDir();
  std::vector<Row> rows;
  const std::string ipc_pub = "ipc://" + run_dir + "/bench.rgbd.ipc";
  const std::string ipc_srv = "ipc://" + run_dir + "/bench.echo.ipc";
  for (double hz : {0.0, 200.0}) {
    rows.push_back(PubSub("ipc", ipc_pub, frames, hz));
    rows.push_back(PubSub("tcp", "tcp://127.0.0.1:*", frames, hz));
  }
  rows.push_back(Service("ipc", ipc_srv, calls));
  rows.push_back(Service("tcp", "tcp://127.0.0.1:*", calls));

  std::printf("%-22s %-4s %8s %6s %6s %6s %10s %9s %9s %9s %8s\n", "test", "tr", "target",
              "sent", "recv", "drops", "rate/s", "p50 ms", "p99 ms", "max ms", "MB/s");
  for (const auto& r : rows) {
    std::printf("%-22s %-4s %8s %6d %6d %6llu %10.1f %9.3f %9.3f %9.3f %8.1f\n", r.test.c_str(),
                r.transport.c_str(),
                r.target_hz > 0 ? std::to_string(static_cast<int>(r.target_hz)).c_str() : "max",
                r.sent, r.received, static_cast<unsigned long long>(r.dropped), r.rate, r.p50_ms,
                r.p99_ms, r.max_ms, r.mb_per_s);
  }
  if (!out_path.empty()) {
    std::ofstream out(out_path);
    if (out_path.size() > 5 && out_path.substr(out_path.size() - 5) == ".json") {
      nlohmann::json j = nlohmann::json::array();
      for (const auto& r : rows) {
        j.push_back({{"test", r.test}, {"transport", r.transport}, {"target_hz", r.target_hz},
                     {"sent", r.sent}, {"received", r.received}, {"dropped", r.dropped},
                     {"malformed", r.malformed}, {"rate_per_s", r.rate}, {"p50_ms", r.p50_ms},
                     {"p99_ms", r.p99_ms}, {"max_ms", r.max_ms}, {"mb_per_s", r.mb_per_s}});
      }
      out << j.dump(2) << "\n";
    } else {
      out << "test,transport,target_hz,sent,received,dropped,malformed,rate_per_s,p50_ms,p99_ms,"
             "max_ms,mb_per_s\n";
      for (const auto& r : rows) {
        out << r.test << "," << r.transport << "," << r.target_hz << "," << r.sent << ","
            << r.received << "," << r.dropped << "," << r.malformed << "," << r.rate << ","
            << r.p50_ms << "," << r.p99_ms << "," << r.max_ms << "," << r.mb_per_s << "\n";
      }
    }
    std::printf("wrote %s\n", out_path.c_str());
  }
  return 0;
}
