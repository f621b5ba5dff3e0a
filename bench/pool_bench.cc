/// @file pool_bench.cc
/// @brief Views/s through p2i_pool with 1 and 2 p2i_synthesizer workers (docs/POOL.md): C
/// client threads each call /render (one pose per request) back to back for D seconds.
///
/// usage: pool_bench [OUT.json] [--workers 1,2] [--clients 4] [--seconds 10] [--size 64]
///                   [--method nearest] [--checkpoint FILE]
/// Each configuration runs in its own P2I_RUN_DIR; processes are the real executables in the
/// folder of this program.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/bench_process.h"
#include "convert/pose.h"
#include "nodes/runtime/service_client.h"
#include "scene/trajectory.h"
#include "util/heap_policy.h"

namespace {

using namespace p2i;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

using bench::Child;
using bench::LoadAverage;

std::vector<int> ParseInts(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, ',')) out.push_back(std::stoi(part));
  return out;
}

struct Options {
  std::string out, method = "nearest", checkpoint;
  std::vector<int> workers = {1, 2};
  int clients = 4, size = 64;
  double seconds = 10;
};

// Returns -1 when parsing succeeded, else the exit code to return.
int ParseArgs(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--workers") o->workers = ParseInts(next());
    else if (a == "--clients") o->clients = std::stoi(next());
    else if (a == "--seconds") o->seconds = std::stod(next());
    else if (a == "--size") o->size = std::stoi(next());
    else if (a == "--method") o->method = next();
    else if (a == "--checkpoint") o->checkpoint = next();
    else if (a[0] != '-') o->out = a;
    else {
      std::fprintf(stderr, "usage: pool_bench [OUT.json] [--workers 1,2] [--clients 4] "
                           "[--seconds 10] [--size 64] [--method nearest] [--checkpoint F]\n");
      return 2;
    }
  }
  return -1;
}

// The pool and k synthesizer workers in run dir `run`; stopped (SIGTERM + wait) on clear().
std::vector<std::unique_ptr<Child>> StartPool(const std::string& bin, const Options& o, int k,
                                              const std::string& run) {
  std::vector<std::unique_ptr<Child>> pids;
  pids.push_back(std::make_unique<Child>(std::vector<std::string>{bin + "/p2i_pool", "status_period:=0"},
                                         run, run + "/pool.log"));
  for (int w = 0; w < k; ++w) {
    std::vector<std::string> a = {bin + "/p2i_synthesizer", "--namespace",
                                  "/w" + std::to_string(w), "-r", "render:=/render",
                                  "method:=" + o.method, "dataset:=builtin:small_office",
                                  "width:=" + std::to_string(o.size),
                                  "height:=" + std::to_string(o.size), "threads:=1",
                                  "pool:={render: ''}"};
    if (!o.checkpoint.empty()) a.push_back("checkpoint:=" + o.checkpoint);
    pids.push_back(std::make_unique<Child>(a, run, run + "/synth" + std::to_string(w) + ".log"));
  }
  return pids;
}

// Warm-up: 4 k requests, so every worker answered at least once. False (error set) on a failure.
bool WarmUp(const runtime::ServiceClientOptions& co, const std::vector<scene::StampedPose>& sweep,
            int k, std::string* error) {
  runtime::ServiceClient<msgs::pb::RenderRequest, msgs::RenderReplyMsg> c("/render", "/bench", co);
  for (int i = 0; i < 4 * k; ++i) {
    msgs::pb::RenderRequest r;
    convert::ToMsg(sweep[i % sweep.size()].pose, r.add_poses());
    msgs::RenderReplyMsg rep;
    std::string why;
    if (!c.Call(r, &rep, &why)) {
      *error = why;
      return false;
    }
  }
  return true;
}

// What the client threads measured.
struct Load {
  std::vector<double> latencies;  // ms, sorted
  int failed = 0;
  double elapsed = 0;  // s
};

// `clients` threads calling /render back to back for `seconds`.
Load RunClients(const runtime::ServiceClientOptions& co, const std::vector<scene::StampedPose>& sweep,
                int clients, double seconds) {
  std::mutex mutex;
  Load load;
  std::atomic<int> failed{0};
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      runtime::ServiceClient<msgs::pb::RenderRequest, msgs::RenderReplyMsg> client(
          "/render", "/bench" + std::to_string(c), co);
      std::vector<double> mine;
      for (size_t i = c; Clock::now() < end; i += clients) {
        msgs::pb::RenderRequest r;
        convert::ToMsg(sweep[i % sweep.size()].pose, r.add_poses());
        msgs::RenderReplyMsg rep;
        std::string error;
        const auto t0 = Clock::now();
        if (client.Call(r, &rep, &error) && rep.meta.ok()) {
          mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        } else {
          ++failed;
        }
      }
      std::lock_guard<std::mutex> lock(mutex);
      load.latencies.insert(load.latencies.end(), mine.begin(), mine.end());
    });
  }
  for (auto& t : threads) t.join();
  load.elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::sort(load.latencies.begin(), load.latencies.end());
  load.failed = failed.load();
  return load;
}

// The table row (printed) and the JSON row of one worker count.
nlohmann::json ReportRow(const Options& o, int k, const Load& m) {
  auto pct = [&](double p) {
    return m.latencies.empty() ? 0.0
                               : m.latencies[std::min(m.latencies.size() - 1,
                                                      static_cast<size_t>(p * m.latencies.size()))];
  };
  const double vps = m.latencies.size() / m.elapsed, load = LoadAverage();
  std::printf("| %d | %d | %d | %s | %zu | %d | %.1f | %.2f | %.2f | %.1f |\n", k, o.clients,
              o.size, o.method.c_str(), m.latencies.size(), m.failed, vps, pct(0.5), pct(0.99),
              load);
  std::fflush(stdout);
  return {{"workers", k}, {"clients", o.clients}, {"size", o.size}, {"method", o.method},
          {"views", m.latencies.size()}, {"failed", m.failed}, {"views_per_s", vps},
          {"p50_ms", pct(0.5)}, {"p99_ms", pct(0.99)}, {"load1", load}};
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("pool_bench")) return 2;  // P2I_HEAP
  Options o;
  const int parse = ParseArgs(argc, argv, &o);
  if (parse >= 0) return parse;
  const std::string bin = fs::canonical("/proc/self/exe").parent_path().string();
  const auto sweep = scene::GenerateArmSweep({});
  nlohmann::json rows = nlohmann::json::array();
  std::printf("| workers | clients | size | method | views | failed | views/s | p50 ms | p99 ms | load |\n"
              "|---|---|---|---|---|---|---|---|---|---|\n");
  for (int k : o.workers) {
    char tmpl[] = "/tmp/p2i-pool-bench-XXXXXX";
    const std::string run = ::mkdtemp(tmpl);
    std::vector<std::unique_ptr<Child>> pids = StartPool(bin, o, k, run);
    ::setenv("P2I_RUN_DIR", run.c_str(), 1);
    runtime::ServiceClientOptions co;
    co.timeout = std::chrono::milliseconds(2000);
    co.retries = 30;
    std::string error;
    if (!WarmUp(co, sweep, k, &error)) {
      std::fprintf(stderr, "warm-up failed: %s (logs in %s)\n", error.c_str(), run.c_str());
      pids.clear();
      return 1;
    }
    rows.push_back(ReportRow(o, k, RunClients(co, sweep, o.clients, o.seconds)));
    pids.clear();
    fs::remove_all(run);
  }
  if (!o.out.empty()) std::ofstream(o.out) << rows.dump(2) << "\n";
  return 0;
}
