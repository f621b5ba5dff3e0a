/// @file model_bench.cc
/// @brief Training step time (phase 1 and 2) and inference latency (p50/p99, batch 1) of P2I-NET
/// for several resolutions and the shipped presets, with parameters, FLOPs and the ratio of the
/// measured time to the time at the machine's measured matmul FLOP rate.
///
/// The matmul rate is measured with the same thread count immediately before and after each
/// timing it divides (median of kMatmulRuns short 512x512 runs on each side), so a ratio compares
/// a timing with the machine's speed at that moment (the shared box's load changes within
/// minutes). The rate used is printed per row and written to the CSV.
///
/// Each training step's time is printed beside its FLOP-limit time (the step's counted FLOPs /
/// the measured matmul rate): `limit ms`. `--profile NAME` (a preset name, e.g. learn_128) then
/// prints where one phase-1 step of that preset goes (G forward, D forward/backward on reals
/// and fakes, Adam, and apart: self-attention and the spectral-norm power iterations).
///
/// usage: model_bench [--threads N] [--out results.csv] [--quick] [--infer-only] [--presets DIR]
///                    [--only NAME] [--profile NAME] [--no-freeze]
/// (--infer-only skips the training-step timings, reported as 0; --only times one row;
/// --no-freeze times the G step with D's weight gradients computed, as before FrozenScope)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "model/model_profiling.h"
#include "model/p2i_config.h"
#include "model/p2i_synthesizer.h"
#include "util/heap_policy.h"
#include "util/order_stats.h"

using namespace p2i;

namespace {

struct Row {
  std::string name;
  model::P2iConfig config;
};

constexpr int kMatmulRuns = 5;  // per side of a timing
constexpr int kMatmulSide = 512;

// The current matmul FLOP rate on `threads`: median of `runs` single timed runs (each with its
// own warm-up), appended to `samples`.
void SampleMatmulRate(int threads, int runs, std::vector<double>* samples) {
  for (int i = 0; i < runs; ++i)
    samples->push_back(model::MeasureMatmulFlopRate(kMatmulSide, threads, /*reps=*/1));
}

using util::Median;

// Runs `timed` between two sets of matmul samples; returns the median rate around it.
template <typename F>
double RateAround(int threads, F&& timed) {
  std::vector<double> samples;
  SampleMatmulRate(threads, kMatmulRuns, &samples);
  timed();
  SampleMatmulRate(threads, kMatmulRuns, &samples);
  return Median(samples);
}

model::P2iConfig Ladder(int res) {
  model::P2iConfig c;
  c.name = "ladder_" + std::to_string(res);
  c.resolution = res;
  c.g_schedule = "custom";
  c.g_widths.clear();
  const std::vector<int> base = {256, 256, 128, 64, 32, 16, 8, 8};
  int stages = 0;
  while ((4 << stages) <= res) ++stages;
  c.g_widths.assign(base.begin(), base.begin() + stages);
  c.enet_width = res >= 256 ? 8 : 16;
  c.enet_blocks = 1;
  c.d_base_width = res >= 256 ? 16 : 32;
  c.d_max_width = 256;
  c.batch_size = res >= 256 ? 8 : 16;
  c.Validate();
  return c;
}

struct Options {
  int threads = 2;
  bool quick = false;
  bool infer_only = false;
  bool freeze_d = true;
  std::string out = "model_bench.csv";
  std::string presets = std::string(P2I_SOURCE_DIR_BENCH) + "/model/presets";
  std::string only, profile;
};

// False (usage printed) on a bad argument.
bool ParseArgs(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--threads" && i + 1 < argc) o->threads = std::atoi(argv[++i]);
    else if (a == "--out" && i + 1 < argc) o->out = argv[++i];
    else if (a == "--presets" && i + 1 < argc) o->presets = argv[++i];
    else if (a == "--only" && i + 1 < argc) o->only = argv[++i];
    else if (a == "--profile" && i + 1 < argc) o->profile = argv[++i];
    else if (a == "--quick") o->quick = true;
    else if (a == "--infer-only") o->infer_only = true;
    else if (a == "--no-freeze") o->freeze_d = false;
    else {
      std::fprintf(stderr, "usage: model_bench [--threads N] [--out CSV] [--quick] [--infer-only] "
                           "[--presets DIR] [--only NAME] [--profile NAME] [--no-freeze]\n");
      return false;
    }
  }
  return true;
}

// --profile NAME: where a phase-1 step of the preset goes, against its FLOP-limit time.
void ProfileStep(const Options& o) {
  const int threads = o.threads;
  const auto config = model::P2iConfig::FromYamlFile(o.presets + "/" + o.profile + ".yaml");
  const int steps = o.quick ? 3 : 8;
  model::StepProfile p;
  const double rate =
      RateAround(threads, [&] { p = model::ProfileTrainingStep(config, steps, threads, o.freeze_d); });
  const double flops = model::TrainingStepFlops(config, 1);
  std::printf("phase-1 step of %s (%dx%d, batch %d) on %d threads, mean of %d steps%s:\n",
              o.profile.c_str(), config.resolution, config.resolution, config.batch_size, threads,
              steps, o.freeze_d ? "" : " (--no-freeze: D not frozen in the G step)");
  for (const auto& [name, sec] : p.sections)
    std::printf("  %-48s %9.1f ms %5.1f %%\n", name.c_str(), sec * 1e3,
                name.rfind("(apart)", 0) == 0 ? 0.0 : 100.0 * sec / p.total);
  std::printf("  %-48s %9.1f ms; FLOP-limit %.1f ms (%.2f GFLOP at %.1f GF/s matmul): %.2fx\n",
              "total", p.total * 1e3, flops / rate * 1e3, flops / 1e9, rate / 1e9,
              p.total / (flops / rate));
}

// One model: render latency and the training steps' times against their FLOP limits, printed
// and as a CSV line.
void BenchModel(const Row& row, const Options& o, const std::string& tmp, std::ofstream& csv) {
  const int threads = o.threads;
  const bool quick = o.quick;
  model::WriteUntrainedCheckpoint(row.config, tmp);
  model::SynthesizerOptions so;
  so.threads = threads;
  auto synth = model::LoadSynthesizer(tmp, so);
  const scene::Pose pose;
  for (int i = 0; i < 3; ++i) synth->Render(pose);
  const int n = quick ? 20 : 100;
  std::vector<double> ms;
  const double infer_rate = RateAround(threads, [&] {
    for (int i = 0; i < n; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      synth->Render(pose);
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
  });
  std::sort(ms.begin(), ms.end());
  const double p50 = ms[ms.size() / 2], p99 = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
  const double flops = synth->FlopsPerView();
  const double infer_ratio = (p50 / 1e3) / (flops / infer_rate);
  const int steps = quick ? 3 : 5;  // odd: the median is one measured step
  double t1 = 0.0, t2 = 0.0, rate1 = 0.0, rate2 = 0.0;
  if (!o.infer_only) {
    rate1 = RateAround(threads, [&] { t1 = model::TimeTrainingStep(row.config, 1, steps, threads, o.freeze_d); });
    if (model::TrainingStepFlops(row.config, 2) > 0)
      rate2 = RateAround(threads, [&] { t2 = model::TimeTrainingStep(row.config, 2, steps, threads); });
  }
  const double f1 = model::TrainingStepFlops(row.config, 1);
  const double f2 = model::TrainingStepFlops(row.config, 2);
  const double t1_ratio = rate1 > 0 ? t1 / (f1 / rate1) : 0.0;
  const double t2_ratio = rate2 > 0 && f2 > 0 ? t2 / (f2 / rate2) : 0.0;
  const double limit1 = rate1 > 0 ? f1 / rate1 : 0.0, limit2 = rate2 > 0 ? f2 / rate2 : 0.0;
  std::printf("%-14s %5d %10lld %8.3f %8.2f %8.2f %8.1f %6.1f %6.2f %10.1f %9.1f %6.1f %6.2f %10.1f %9.1f %6.1f %6.2f\n",
              row.name.c_str(), row.config.resolution,
              static_cast<long long>(synth->ParameterCount()), flops / 1e9, p50, p99, 1e3 / p50,
              infer_rate / 1e9, infer_ratio, t1 * 1e3, limit1 * 1e3, rate1 / 1e9, t1_ratio,
              t2 * 1e3, limit2 * 1e3, rate2 / 1e9, t2_ratio);
  std::fflush(stdout);
  csv << row.name << "," << row.config.resolution << "," << threads << ","
      << synth->ParameterCount() << "," << flops / 1e9 << "," << p50 << "," << p99 << ","
      << 1e3 / p50 << "," << infer_ratio << "," << infer_rate / 1e9 << "," << t1 * 1e3 << ","
      << t1_ratio << "," << rate1 / 1e9 << "," << t2 * 1e3 << "," << t2_ratio << ","
      << rate2 / 1e9 << "," << limit1 * 1e3 << "," << limit2 * 1e3 << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("model_bench")) return 2;  // P2I_HEAP
  Options o;
  if (!ParseArgs(argc, argv, &o)) return 1;
  std::printf("matmul rate: %dx%d on %d threads, median of %d runs before + %d after each "
              "timing (mm GF/s columns)\n",
              kMatmulSide, kMatmulSide, o.threads, kMatmulRuns, kMatmulRuns);
  std::vector<Row> rows;
  for (int r : {64, 128, 256}) rows.push_back({"ladder_" + std::to_string(r), Ladder(r)});
  if (!o.profile.empty()) {
    ProfileStep(o);
    return 0;
  }
  for (const std::string name : {"default", "default_256", "cnn_baseline", "learn_64", "learn_128"}) {
    const std::string path = o.presets + "/" + name + ".yaml";
    if (std::filesystem::exists(path)) rows.push_back({name, model::P2iConfig::FromYamlFile(path)});
  }
  const auto tmp = std::filesystem::temp_directory_path() / "p2i_model_bench.pt";
  std::ofstream csv(o.out);
  csv << "name,resolution,threads,params,gflops_per_view,p50_ms,p99_ms,views_per_s,"
         "infer_ratio_to_matmul,infer_matmul_gflops,train1_ms,train1_ratio,train1_matmul_gflops,"
         "train2_ms,train2_ratio,train2_matmul_gflops,train1_limit_ms,train2_limit_ms\n";
  std::printf("%-14s %5s %10s %8s %8s %8s %8s %6s %6s %10s %9s %6s %6s %10s %9s %6s %6s\n", "model",
              "res", "params", "GFLOP/v", "p50 ms", "p99 ms", "views/s", "mmGF/s", "ratio",
              "train1 ms", "limit ms", "mmGF/s", "ratio", "train2 ms", "limit ms", "mmGF/s", "ratio");
  for (const auto& row : rows) {
    if (!o.only.empty() && row.name != o.only) continue;
    BenchModel(row, o, tmp.string(), csv);
  }
  std::filesystem::remove(tmp);
  std::printf("wrote %s\n", o.out.c_str());
  return 0;
}
