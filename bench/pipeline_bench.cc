/// @file pipeline_bench.cc
/// @brief End-to-end serving benchmark: request-to-view latency (p50/p99) and views/s through
/// the real p2i_synthesizer process (render service, one pose per request, one client), at
/// several resolutions, with and without a p2i_trainer process training at the same time.
/// Prints a table and writes CSV or JSON.
///
/// usage: pipeline_bench [OUT.csv|OUT.json] [--sizes 64,128,256] [--requests N] [--warmup N]
///                       [--trainer off|on|both] [--synth-threads N] [--trainer-threads N]
///                       [--trainer-data DIR] [--work DIR]
///
/// Models: untrained P2I-NETs from the shipped presets (64: demo_64, 128: default, 256:
/// default_256), made with `p2i train PRESET --data procedural --steps 0 --phase 1` (random
/// weights; the render cost does not depend on training). The trainer, when on, trains the
/// demo_64 preset offline on --trainer-data (default: builtin:small_office along the arm sweep,
/// 120 frames at 160x120, rendered by `p2i render`) in one endless round (threads --trainer-threads), started and warmed up
/// (training steps logged) before the measurement. Every process runs with its own
/// P2I_RUN_DIR; the synthesizer is started with topic_mode false, max_batch 1.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/bench_process.h"
#include "convert/pose.h"
#include "msgs/codec.h"
#include "nodes/runtime/service_client.h"
#include "scene/trajectory.h"
#include "util/heap_policy.h"

namespace {

using namespace p2i;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

struct Row {
  int size = 0;
  bool trainer = false;
  int requests = 0, failures = 0;
  double views_per_s = 0;
  double p50_ms = 0, p99_ms = 0, max_ms = 0;
  double render_p50_ms = 0, queue_p50_ms = 0;  // as reported by the synthesizer
  double trainer_steps_per_s = 0;              // over all sizes of this mode (0 = no trainer)
  double load1 = 0;                            // 1-minute load average at the end
};

using bench::Child;
using bench::LoadAverage;
using bench::Percentile;

int Run(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// The highest "step" logged in a train_log.jsonl (the trainer logs every few steps).
int LastLoggedStep(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  int step = 0;
  while (std::getline(in, line)) {
    const size_t at = line.find("\"step\":");
    if (at != std::string::npos && line.find("\"loss") != std::string::npos)
      step = std::max(step, std::atoi(line.c_str() + at + 7));
  }
  return step;
}

/// N from the trainer's "training stopped after X s at step N" log line (-1 if absent).
int StoppedAtStep(const std::string& log) {
  std::ifstream in(log);
  std::string line;
  int step = -1;
  while (std::getline(in, line)) {
    const size_t at = line.find("training stopped after");
    if (at == std::string::npos) continue;
    const size_t s = line.find("at step ", at);
    if (s != std::string::npos) step = std::atoi(line.c_str() + s + 8);
  }
  return step;
}

int CountLines(const std::string& path, const std::string& needle) {
  std::ifstream in(path);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) n += line.find(needle) != std::string::npos;
  return n;
}

std::string Preset(const std::string& src, int size) {
  if (size == 64) return src + "/model/presets/demo_64.yaml";
  if (size == 128) return src + "/model/presets/default.yaml";
  if (size == 256) return src + "/model/presets/default_256.yaml";
  throw std::invalid_argument("no preset for size " + std::to_string(size) + " (64, 128, 256)");
}

// A failed step: main prints the message and exits 1.
struct BenchFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string out_path, trainer_mode = "both", trainer_data, work;
  std::vector<int> sizes{64, 128, 256};
  int requests = 300, warmup = 20, synth_threads = 1, trainer_threads = 1;
};

// Returns -1 when parsing succeeded, else the exit code to return.
int ParseArgs(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--sizes") {
      o->sizes.clear();
      std::stringstream ss(next());
      std::string tok;
      while (std::getline(ss, tok, ',')) o->sizes.push_back(std::atoi(tok.c_str()));
    } else if (a == "--requests") {
      o->requests = std::atoi(next().c_str());
    } else if (a == "--warmup") {
      o->warmup = std::atoi(next().c_str());
    } else if (a == "--trainer") {
      o->trainer_mode = next();
    } else if (a == "--synth-threads") {
      o->synth_threads = std::atoi(next().c_str());
    } else if (a == "--trainer-threads") {
      o->trainer_threads = std::atoi(next().c_str());
    } else if (a == "--trainer-data") {
      o->trainer_data = next();
    } else if (a == "--work") {
      o->work = next();
    } else if (a == "-h" || a == "--help" || a[0] == '-') {
      std::printf(
          "usage: %s [OUT.csv|OUT.json] [--sizes 64,128,256] [--requests N] [--warmup N]\n"
          "          [--trainer off|on|both] [--synth-threads N] [--trainer-threads N]\n"
          "          [--trainer-data DIR] [--work DIR]\n",
          argv[0]);
      return a[0] == '-' && a != "-h" && a != "--help" ? 2 : 0;
    } else {
      o->out_path = a;
    }
  }
  if (o->trainer_mode != "off" && o->trainer_mode != "on" && o->trainer_mode != "both") {
    std::fprintf(stderr, "--trainer must be off, on or both\n");
    return 2;
  }
  return -1;
}

// Where the programs, presets and the work folder are.
struct Paths {
  std::string bin, src, work;
};

// Models (untrained, from the presets).
void MakeModels(const Paths& p, const std::vector<int>& sizes) {
  for (int size : sizes) {
    const std::string dir = p.work + "/model_" + std::to_string(size);
    if (fs::exists(dir + "/checkpoint.pt")) continue;
    const std::string cmd = "'" + p.bin + "/p2i' train '" + Preset(p.src, size) +
                            "' --data procedural --frames 8 --steps 0 --phase 1 --threads 1 "
                            "--quiet --out '" + dir + "' > '" + dir + ".log' 2>&1";
    fs::create_directories(dir);
    if (Run(cmd) != 0)
      throw BenchFailure("making the " + std::to_string(size) + " model failed: see " + dir + ".log");
  }
}

// The trainer's data: --trainer-data, else rendered once into the work folder.
std::string TrainerData(const Paths& p, std::string trainer_data) {
  if (!trainer_data.empty()) return trainer_data;
  trainer_data = p.work + "/trainer_data";
  if (!fs::exists(trainer_data)) {
    const std::string cmd = "'" + p.bin + "/p2i' render builtin:small_office -t arm_sweep "
                            "--width 160 --height 120 --max-frames 120 --out '" +
                            trainer_data + "' > '" + p.work + "/render.log' 2>&1";
    if (Run(cmd) != 0)
      throw BenchFailure("rendering trainer data failed: see " + p.work + "/render.log");
  }
  if (fs::exists(trainer_data + "/seq-01")) trainer_data += "/seq-01";
  return trainer_data;
}

// The trainer process, started and warmed up (stepping), with the step and time it was at then.
struct TrainerRun {
  std::unique_ptr<Child> child;
  Clock::time_point t0;
  int step0 = 0;
};

TrainerRun StartTrainer(const Paths& p, const Options& o, const std::string& trainer_data) {
  const std::string trainer_run = p.work + "/run_trainer";
  const std::string trainer_work = p.work + "/trainer_work";
  fs::remove_all(trainer_work);
  fs::create_directories(trainer_run);
  TrainerRun t;
  t.child = std::make_unique<Child>(
      std::vector<std::string>{p.bin + "/p2i_trainer", "dataset:=" + trainer_data,
                               "config:=" + p.src + "/model/presets/demo_64.yaml",
                               "work_dir:=" + trainer_work, "publish_every_steps:=1000000",
                               "threads:=" + std::to_string(o.trainer_threads),
                               "status_period:=0"},
      trainer_run, p.work + "/trainer.log");
  // Warm up: the trainer is past its set-up and stepping.
  const auto deadline = Clock::now() + std::chrono::minutes(5);
  while (Clock::now() < deadline && t.child->Running() &&
         CountLines(trainer_work + "/train_log.jsonl", "\"loss") < 2)
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  if (!t.child->Running() || CountLines(trainer_work + "/train_log.jsonl", "\"loss") < 2)
    throw BenchFailure("the trainer did not start training: see " + p.work + "/trainer.log");
  t.t0 = Clock::now();
  t.step0 = LastLoggedStep(trainer_work + "/train_log.jsonl");
  return t;
}

// Stops the trainer; its speed (steps from the end of the warm-up to the stop, over that time)
// goes on every row measured with it.
void StopTrainer(const Paths& p, TrainerRun* t, std::vector<Row>* rows) {
  const double seconds = std::chrono::duration<double>(Clock::now() - t->t0).count();
  t->child->Stop();
  const int end_step = StoppedAtStep(p.work + "/trainer.log");
  const double rate = end_step >= 0 ? (end_step - t->step0) / seconds : 0.0;
  for (auto& r : *rows)
    if (r.trainer) r.trainer_steps_per_s = rate;
  std::fprintf(stderr, "trainer: steps %d -> %d in %.1f s (%.2f steps/s)\n", t->step0, end_step,
               seconds, rate);
}

// One size: a synthesizer process, warm-up requests, then the measured ones.
Row MeasureSize(const Paths& p, const Options& o, const std::vector<scene::StampedPose>& sweep,
                int size, bool with_trainer) {
  const std::string run = p.work + "/run_" + std::to_string(size);
  fs::create_directories(run);
  Child synth({p.bin + "/p2i_synthesizer", "method:=p2i",
               "checkpoint:=" + p.work + "/model_" + std::to_string(size) + "/checkpoint.pt",
               "dataset:=builtin:small_office", "width:=" + std::to_string(size),
               "height:=" + std::to_string(size), "threads:=" + std::to_string(o.synth_threads),
               "topic_mode:=false", "max_batch:=1", "status_period:=0"},
              run, p.work + "/synth_" + std::to_string(size) + ".log");
  runtime::ServiceClientOptions co;
  co.endpoint = "ipc://" + run + "/service.render.ipc";
  co.timeout = std::chrono::milliseconds(10000);
  co.retries = 6;  // the first call waits for the model to load
  runtime::ServiceClient<msgs::pb::RenderRequest, msgs::RenderReplyMsg> client(
      "/render", "/pipeline_bench", co);
  Row row;
  row.size = size;
  row.trainer = with_trainer;
  std::vector<double> latency, render, queue;
  Clock::time_point t0;
  for (int i = 0; i < o.warmup + o.requests; ++i) {
    if (i == o.warmup) t0 = Clock::now();
    msgs::pb::RenderRequest req;
    convert::ToMsg(sweep[i % sweep.size()].pose, req.add_poses());
    msgs::RenderReplyMsg reply;
    std::string error;
    const auto s = Clock::now();
    const bool ok = client.Call(req, &reply, &error) && reply.meta.ok() &&
                    reply.images.size() == 2 && reply.images[0].width == uint32_t(size);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - s).count();
    if (!ok) {
      if (i < o.warmup)
        throw BenchFailure("size " + std::to_string(size) + ": " + error + reply.meta.error());
      ++row.failures;
      continue;
    }
    if (i < o.warmup) continue;
    latency.push_back(ms);
    render.push_back(reply.meta.views(0).render_ms());
    queue.push_back(reply.meta.views(0).queue_ms());
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  synth.Stop();
  row.requests = o.requests;
  row.views_per_s = latency.size() / seconds;
  row.p50_ms = Percentile(latency, 50);
  row.p99_ms = Percentile(latency, 99);
  row.max_ms = Percentile(latency, 100);
  row.render_p50_ms = Percentile(render, 50);
  row.queue_p50_ms = Percentile(queue, 50);
  row.load1 = LoadAverage();
  std::fprintf(stderr, "size %d, trainer %s: %.1f views/s, p50 %.2f ms, p99 %.2f ms\n", size,
               with_trainer ? "on" : "off", row.views_per_s, row.p50_ms, row.p99_ms);
  return row;
}

void PrintTable(const std::vector<Row>& rows) {
  std::printf("\n| size | trainer | requests | failures | views/s | p50 ms | p99 ms | max ms | "
              "render p50 ms | queue p50 ms | trainer steps/s | load1 |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    std::printf("| %d | %s | %d | %d | %.1f | %.2f | %.2f | %.2f | %.2f | %.3f | %.2f | %.2f |\n",
                r.size, r.trainer ? "on" : "off", r.requests, r.failures, r.views_per_s,
                r.p50_ms, r.p99_ms, r.max_ms, r.render_p50_ms, r.queue_p50_ms,
                r.trainer_steps_per_s, r.load1);
  }
}

// OUT.json (an array of rows) or CSV.
void WriteRows(const std::string& out_path, const std::vector<Row>& rows) {
  std::ofstream out(out_path);
  if (out_path.size() > 5 && out_path.substr(out_path.size() - 5) == ".json") {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& r : rows) {
      j.push_back({{"size", r.size}, {"trainer", r.trainer}, {"requests", r.requests},
                   {"failures", r.failures}, {"views_per_s", r.views_per_s},
                   {"p50_ms", r.p50_ms}, {"p99_ms", r.p99_ms}, {"max_ms", r.max_ms},
                   {"render_p50_ms", r.render_p50_ms}, {"queue_p50_ms", r.queue_p50_ms},
                   {"trainer_steps_per_s", r.trainer_steps_per_s}, {"load1", r.load1}});
    }
    out << j.dump(2) << "\n";
  } else {
    out << "size,trainer,requests,failures,views_per_s,p50_ms,p99_ms,max_ms,render_p50_ms,"
           "queue_p50_ms,trainer_steps_per_s,load1\n";
    for (const auto& r : rows) {
      out << r.size << "," << (r.trainer ? "on" : "off") << "," << r.requests << ","
          << r.failures << "," << r.views_per_s << "," << r.p50_ms << "," << r.p99_ms << ","
          << r.max_ms << "," << r.render_p50_ms << "," << r.queue_p50_ms << ","
          << r.trainer_steps_per_s << "," << r.load1 << "\n";
    }
  }
  std::printf("wrote %s\n", out_path.c_str());
}

// Every mode (without, then with the trainer) x size.
std::vector<Row> MeasureAll(const Paths& p, const Options& o, const std::string& trainer_data) {
  const auto sweep = scene::GenerateArmSweep({});
  std::vector<Row> rows;
  std::vector<bool> modes;
  if (o.trainer_mode != "on") modes.push_back(false);
  if (o.trainer_mode != "off") modes.push_back(true);
  for (bool with_trainer : modes) {
    TrainerRun trainer;
    if (with_trainer) trainer = StartTrainer(p, o, trainer_data);
    for (int size : o.sizes) rows.push_back(MeasureSize(p, o, sweep, size, with_trainer));
    if (trainer.child) StopTrainer(p, &trainer, &rows);
  }
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("pipeline_bench")) return 2;  // P2I_HEAP
  Options o;
  const int parse = ParseArgs(argc, argv, &o);
  if (parse >= 0) return parse;
  Paths p;
  p.bin = fs::canonical("/proc/self/exe").parent_path().string();
  p.src = P2I_SOURCE_DIR;
  p.work = o.work.empty() ? "/tmp/p2i_pipeline_bench_" + std::to_string(::getpid()) : o.work;
  fs::create_directories(p.work);
  try {
    MakeModels(p, o.sizes);
    const std::string trainer_data = o.trainer_mode != "off" ? TrainerData(p, o.trainer_data) : "";
    const std::vector<Row> rows = MeasureAll(p, o, trainer_data);
    PrintTable(rows);
    if (!o.out_path.empty()) WriteRows(o.out_path, rows);
  } catch (const BenchFailure& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
