/// @file bench_stages.cc
#include "eval/bench_stages.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "eval/sim_ceiling.h"
#include "eval/strips.h"
#include "model/coverage.h"
#include "model/densify.h"
#include "model/method_registry.h"
#include "model/metrics.h"
#include "model/pose_dependence.h"
#include "model/trainer.h"
#include "scene/capture.h"
#include "scene/dataset_loader.h"
#include "scene/image_ops.h"
#include "scene/splits.h"
#include "scene/trajectory.h"

namespace p2i::eval {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M:%S", std::gmtime(&t));
  return buf;
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  in >> a >> b >> c;
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.2f %.2f %.2f", a, b, c);
  return buf;
}

std::string Fixed(double v, int digits = 2) {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// ---------------------------------------------------------------- data
// How a sim scene's frames were rendered, for the report.
std::string SensorDescription(const scene::SimScene& sim) {
  const scene::SimSensorOptions& o = sim.sensor_options();
  std::string s = sim.description().AnyViewDependent() ? "specular materials" : "Lambertian";
  if (!o.AnyEnabled()) return s + ", exact: no sensor effects";
  if (o.AnyNoise()) {
    s += ", depth noise " + Fixed(o.depth_noise_sigma * 1000, 1) + " mm + " +
         Fixed(o.depth_noise_quadratic * 1000, 1) + " mm/m^2, range " + Fixed(o.min_range, 1) +
         "-" + Fixed(o.max_range, 1) + " m, holes beyond " + Fixed(o.grazing_angle_deg, 0) +
         " deg, dropout " + Fixed(o.depth_dropout * 100, 1) + " %, RGB noise " +
         Fixed(o.rgb_noise_sigma, 1);
  }
  if (o.AnyColour()) {
    s += ", auto-exposure " + Fixed(o.auto_exposure, 2) + ", exposure drift " +
         Fixed(o.exposure_drift * 100, 0) + " %, white-balance drift " +
         Fixed(o.white_balance_drift * 100, 0) + " %";
  }
  if (o.MotionBlur()) s += ", motion blur over " + Fixed(o.exposure_time_s * 1000, 0) + " ms";
  if (o.PixelArea())
    s += ", pixel area " + std::to_string(o.pixel_samples) + "x" + std::to_string(o.pixel_samples);
  return s + ", sensor seed " + std::to_string(o.seed);
}

struct Data {
  scene::DatasetIndex index;
  std::optional<scene::SimScene> sim;  // set for sim scenes: exact ground truth anywhere
  std::string description;
};

// The sim scene rendered along the config's adjacent arm sweeps into OUT/dataset.
void RenderSimData(const BenchConfig& c, const std::string& out_dir, Data* data) {
  const auto& d = c.dataset;
  data->sim = scene::SimScene::FromSpec(d.scene);
  if (!d.specular) data->sim = data->sim->Lambertian();
  data->sim->set_sensor_options(d.sensor);
  int side = d.render_size;
  for (const auto& s : c.sizes) side = std::max({side, s.Width(), s.Height()});
  const scene::CameraInfo camera = scene::SimScene::DefaultCamera(side, side);
  scene::AdjacentSweepsOptions sweeps;
  sweeps.sweep.heights = d.heights;
  sweeps.sweep.speed = d.speed;
  sweeps.count = d.trajectories;
  sweeps.offset = d.trajectory_offset;
  sweeps.Validate();
  const auto trajectories = scene::GenerateAdjacentSweeps(sweeps);
  const fs::path root = fs::path(out_dir) / "dataset";
  fs::remove_all(root);  // deterministic: re-rendered identically on a resumed run
  size_t total = 0;
  for (size_t k = 0; k < trajectories.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "seq-%02zu", k + 1);
    scene::CaptureWriter writer((root / name).string(), camera, {true, false});
    int kept = 0;
    for (size_t i = 0; i < trajectories[k].size(); i += d.frame_step) {
      if (d.max_frames > 0 && kept >= d.max_frames) break;
      writer.Append(data->sim->RenderOnTrajectory(trajectories[k], i, camera));
      ++kept;
    }
    total += kept;
  }
  data->index = scene::OpenDataset(root.string());
  data->description = "sim scene `" + d.scene + "`, " + std::to_string(trajectories.size()) +
                      " adjacent arm sweeps (" + Fixed(d.trajectory_offset, 2) + " m apart), " +
                      std::to_string(total) + " frames rendered at " + std::to_string(side) + "x" +
                      std::to_string(side) + " (" + SensorDescription(*data->sim) + ")";
}

// A dataset folder, every frame_step-th frame, at most max_frames per sequence.
void ReadFolderData(const BenchConfig& c, Data* data) {
  const auto& d = c.dataset;
  scene::DatasetOptions o;
  o.format = d.format;
  o.seven_scenes_invalid_depth = d.seven_scenes_invalid_depth;
  scene::DatasetIndex all = scene::OpenDataset(d.path, o);
  if (!d.sequences.empty()) {
    try {
      all = all.SelectSequences(d.sequences);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error("dataset.sequences of '" + d.path + "': " + e.what());
    }
  }
  std::vector<scene::FrameRef> frames;
  std::map<std::string, int> seen, kept;
  for (const auto& f : all.frames()) {
    const int i = seen[f.sequence]++;
    if (i % d.frame_step != 0) continue;
    if (d.max_frames > 0 && kept[f.sequence] >= d.max_frames) continue;
    ++kept[f.sequence];
    frames.push_back(f);
  }
  data->index = scene::DatasetIndex(all.camera(), all.depth_encoding(), frames);
  data->description = "dataset folder `" + d.path + "` (" + scene::DetectDatasetFormat(d.path) +
                      "), " + std::to_string(frames.size()) + " frames in " +
                      std::to_string(data->index.Sequences().size()) + " sequence(s)";
}

Data PrepareData(const BenchConfig& c, const std::string& out_dir, bool quiet) {
  Data data;
  if (c.dataset.IsSim()) {
    RenderSimData(c, out_dir, &data);
  } else {
    ReadFolderData(c, &data);
  }
  if (!quiet) std::printf("data: %s\n", data.description.c_str());
  return data;
}

scene::Split MakeSplit(const BenchConfig& c, const scene::DatasetIndex& index,
                       const scene::EvalSetting& setting) {
  const auto seqs = index.Sequences();
  scene::Split split;
  if (setting.split == scene::SplitSetting::kMissingFrames) {
    split = scene::MakeMissingFramesSplit(index, setting.held_out, c.period);
    if (split.test.empty())
      throw std::invalid_argument(c.source + ": setting " + setting.Name() +
                               " holds out no frame (every sequence is shorter than period + N = " +
                               std::to_string(c.period + setting.held_out) +
                               " frames): lower 'period' or use more frames");
  } else if (setting.split == scene::SplitSetting::kAdjacentTrajectory) {
    if (seqs.size() < 2 && c.b_train.empty())
      throw std::invalid_argument(c.source + ": setting b needs 2 sequences; the data has " +
                               std::to_string(seqs.size()) + " (add split_b or trajectories)");
    split = scene::MakeAdjacentTrajectorySplit(index, c.b_train.empty() ? seqs[0] : c.b_train,
                                               c.b_test.empty() ? seqs[1] : c.b_test);
  } else {
    std::vector<std::string> train = c.c_train, test = c.c_test;
    if (train.empty()) {
      if (seqs.size() < 3)
        throw std::invalid_argument(c.source + ": setting c needs 3 sequences by default; the data has " +
                                 std::to_string(seqs.size()) + " (add split_c: {train, test})");
      test = {seqs[seqs.size() / 2]};
      for (const auto& s : seqs)
        if (s != test[0]) train.push_back(s);
    }
    split = scene::MakeCrossTrajectorySplit(index, train, test);
  }
  return split;
}

std::vector<std::string> Subsample(const std::vector<std::string>& ids, size_t max_count) {
  if (ids.size() <= max_count) return ids;
  std::vector<std::string> out;
  for (size_t i = 0; i < max_count; ++i) {
    const size_t j = max_count == 1 ? 0 : (i * (ids.size() - 1) + (max_count - 1) / 2) / (max_count - 1);
    out.push_back(ids[j]);
  }
  return out;
}

// Frames centre-cropped and resized to a view size, loaded once.
class FrameCache {
 public:
  explicit FrameCache(const scene::DatasetIndex& index) : index_(index) {}
  scene::RgbdDataset Get(const std::vector<std::string>& ids, const SizeSpec& size) {
    const int w = size.Width(), h = size.Height();
    scene::RgbdDataset out;
    out.camera = scene::CenterCropResizeCamera(index_.camera(), w, h);
    auto& cache = cache_[{w, h}];
    for (const auto& id : ids) {
      auto it = cache.find(id);
      if (it == cache.end()) {
        const int i = index_.Find(id);
        if (i < 0) throw std::runtime_error("frame " + id + " not in the dataset");
        it = cache.emplace(id, scene::CenterCropResizeSample(index_.Load(i), w, h)).first;
      }
      out.frames.push_back(it->second);
    }
    return out;
  }

 private:
  const scene::DatasetIndex& index_;
  std::map<std::pair<int, int>, std::map<std::string, scene::RgbdSample>> cache_;
};

// ---------------------------------------------------------------- evaluation
void Evaluate(model::ViewSynthesizer& method, const scene::RgbdDataset& test,
              const model::LpipsSqueeze* lpips, const model::CoverageScorer& coverage,
              int threads, ResultRow* row) {
  // Warm-up (first-call allocations are not part of the latency).
  for (int i = 0; i < 2 && !test.frames.empty(); ++i) (void)method.Render(test.frames[0].pose);
  model::LatencyRecorder rec(threads);
  double sum_abs_rel = 0, sum_sq = 0;
  int64_t valid = 0, gt_valid = 0;
  std::vector<double> psnr, ssim, lp, cov;
  model::PoseDependence dependence;
  row->views.clear();
  for (const auto& gt : test.frames) {
    rec.Start();
    scene::RgbdSample v = method.Render(gt.pose);
    rec.Stop();
    if (v.rgb.size() != gt.rgb.size()) cv::resize(v.rgb, v.rgb, gt.rgb.size(), 0, 0, cv::INTER_AREA);
    if (!v.depth.empty() && v.depth.size() != gt.depth.size())
      cv::resize(v.depth, v.depth, gt.depth.size(), 0, 0, cv::INTER_NEAREST_EXACT);
    ViewRecord rec_view;
    rec_view.id = gt.id;
    rec_view.psnr = model::Psnr(v.rgb, gt.rgb);
    rec_view.ssim = model::Ssim(v.rgb, gt.rgb);
    dependence.Add(v.rgb, gt.rgb);
    rec_view.lpips = lpips ? lpips->Distance(v.rgb, gt.rgb) : std::nan("");
    rec_view.coverage = coverage.Score(gt.pose);
    if (!v.depth.empty()) {
      const auto de = model::ComputeDepthErrors(v.depth, gt.depth);
      if (de.valid_pixels > 0) {
        sum_abs_rel += de.abs_rel * de.valid_pixels;
        sum_sq += de.rmse_m * de.rmse_m * de.valid_pixels;
      }
      valid += de.valid_pixels;
      gt_valid += de.gt_valid_pixels;
    }
    psnr.push_back(rec_view.psnr);
    ssim.push_back(rec_view.ssim);
    lp.push_back(rec_view.lpips);
    cov.push_back(rec_view.coverage);
    row->views.push_back(rec_view);
  }
  const auto lat = rec.Summary();
  row->test_views = static_cast<int>(test.frames.size());
  row->psnr = ComputeSpread(psnr).mean;
  row->ssim = ComputeSpread(ssim).mean;
  row->lpips = lpips ? ComputeSpread(lp).mean : std::nan("");
  row->depth_abs_rel = valid > 0 ? sum_abs_rel / valid : std::nan("");
  row->depth_rmse_m = valid > 0 ? std::sqrt(sum_sq / valid) : std::nan("");
  row->depth_valid_fraction = gt_valid > 0 ? double(valid) / gt_valid : std::nan("");
  row->views_per_s = lat.views_per_second;
  row->latency_p50_ms = lat.p50_ms;
  row->latency_p99_ms = lat.p99_ms;
  row->threads = threads;
  row->coverage_spearman = SpearmanRho(cov, psnr);
  row->pose_dependence = dependence.Score();
  row->params = static_cast<double>(method.ParameterCount());
  row->flops_per_view = method.FlopsPerView();
}

// ---------------------------------------------------------------- stability
// Per-sample figures are appended to `views_csv` (stability_views.csv: one line per method and
// perturbed pose) so that outliers behind a mean can be inspected.
std::vector<StabilityPoint> RunStability(model::ViewSynthesizer& method, const std::string& name,
                                         const std::vector<StabilitySample>& samples,
                                         const std::string& views_csv) {
  std::map<std::pair<std::string, double>, std::vector<double>> psnr, ssim, dist;
  const bool header = !fs::exists(views_csv);
  std::ofstream lines(views_csv, std::ios::app);
  if (header) lines << "method,kind,offset,sample,psnr_db,nearest_distance,tx,ty,tz,qx,qy,qz,qw\n";
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto& s = samples[i];
    scene::RgbdSample v = method.Render(s.pose);
    if (v.rgb.size() != s.gt.rgb.size()) cv::resize(v.rgb, v.rgb, s.gt.rgb.size(), 0, 0, cv::INTER_AREA);
    const auto key = std::make_pair(s.kind, s.offset);
    const double p = model::Psnr(v.rgb, s.gt.rgb);
    const auto x = s.pose.ToVector7();
    lines << name << ',' << s.kind << ',' << s.offset << ',' << i << ',' << p << ',' << s.nearest;
    for (int k = 0; k < 7; ++k) lines << ',' << x[k];
    lines << '\n';
    psnr[key].push_back(p);
    ssim[key].push_back(model::Ssim(v.rgb, s.gt.rgb));
    dist[key].push_back(s.nearest);
  }
  std::vector<StabilityPoint> out;
  for (const auto& [key, values] : psnr) {
    StabilityPoint p;
    p.method = name;
    p.kind = key.first;
    p.offset = key.second;
    p.psnr = ComputeSpread(values).mean;
    p.ssim = ComputeSpread(ssim[key]).mean;
    p.nearest_distance = ComputeSpread(dist[key]).mean;
    p.n = static_cast<int>(values.size());
    out.push_back(p);
  }
  return out;
}

void SaveStability(const std::string& out_dir, const std::vector<StabilityPoint>& points) {
  nlohmann::json arr = nlohmann::json::array();
  std::string csv = "method,kind,offset,psnr_db,ssim,nearest_distance,n\n";
  for (const auto& p : points) {
    arr.push_back({{"method", p.method}, {"kind", p.kind}, {"offset", p.offset},
                   {"psnr_db", p.psnr}, {"ssim", p.ssim}, {"nearest_distance", p.nearest_distance},
                   {"n", p.n}});
    char buf[256];
    std::snprintf(buf, sizeof(buf), "%s,%s,%.6g,%.6g,%.6g,%.6g,%d\n", p.method.c_str(),
                  p.kind.c_str(), p.offset, p.psnr, p.ssim, p.nearest_distance, p.n);
    csv += buf;
  }
  scene::WriteFileAtomic(out_dir + "/stability.json", arr.dump(1) + "\n");
  scene::WriteFileAtomic(out_dir + "/stability.csv", csv);
}

std::vector<StabilityPoint> LoadStability(const std::string& out_dir) {
  std::vector<StabilityPoint> out;
  const std::string path = out_dir + "/stability.json";
  if (!fs::exists(path)) return out;
  std::ifstream in(path);
  try {
    for (const auto& j : nlohmann::json::parse(in)) {
      StabilityPoint p;
      p.method = j.at("method");
      p.kind = j.at("kind");
      p.offset = j.at("offset");
      p.psnr = j.at("psnr_db").is_null() ? NAN : j.at("psnr_db").get<double>();
      p.ssim = j.at("ssim").is_null() ? NAN : j.at("ssim").get<double>();
      p.nearest_distance = j.value("nearest_distance", 0.0);
      p.n = j.value("n", 0);
      out.push_back(p);
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": malformed: " + e.what());
  }
  return out;
}


// ---------------------------------------------------------------- measurements
// What RunMeasurements' stages share: the run, the data, the frame cache, the progress count.
struct Measurement {
  Measurement(BenchRun& r, Data d) : run(r), data(std::move(d)), cache(data.index) {}
  BenchRun& run;
  Data data;
  FrameCache cache;
  size_t done = 0, total = 0;
};

// What the runs of one setting x size share.
struct SizeRuns {
  const scene::EvalSetting* setting = nullptr;
  const SizeSpec* size = nullptr;
  scene::RgbdDataset train, test;
  std::vector<scene::Pose> train_poses;
  std::unique_ptr<model::CoverageScorer> coverage;
  std::vector<std::string> strip_ids;
  std::string strip_dir;
  bool strip_size = false;      // the strip views are rendered at this size
  bool stability_here = false;  // the stability sweep runs on this setting and size
  std::optional<std::vector<StabilitySample>> stability_samples;  // made at first use
};

bool AnyRunAt(const BenchConfig& c, const scene::EvalSetting& setting, const SizeSpec& size) {
  bool any_run = false;
  for (const auto& m : c.methods) any_run = any_run || !c.RunsOf(m, setting, size).empty();
  return any_run;
}

size_t CountRuns(const BenchConfig& c) {
  size_t total = 0;
  for (const auto& setting : c.settings)
    for (const auto& size : c.sizes) {
      for (const auto& m : c.methods) total += c.RunsOf(m, setting, size).size();
      if (AnyRunAt(c, setting, size)) total += c.ceiling.size();  // ceiling rows (sim only)
    }
  return total;
}

// The frames, coverage scorer, strip and stability plan of one setting x size; saves the ground
// truth strip views at the strip size.
void PrepareSize(Measurement& ms, const scene::Split& split, const std::vector<std::string>& test_ids,
                 SizeRuns* sr) {
  const BenchConfig& c = ms.run.config;
  sr->train = ms.cache.Get(split.train, *sr->size);
  sr->test = ms.cache.Get(test_ids, *sr->size);
  for (const auto& f : sr->train.frames) sr->train_poses.push_back(f.pose);
  sr->coverage = std::make_unique<model::CoverageScorer>(sr->train_poses);
  if (sr->strip_size) {
    const auto gt = ms.cache.Get(sr->strip_ids, *sr->size);
    for (size_t k = 0; k < gt.frames.size(); ++k)
      SaveStripView(sr->strip_dir + "/ground_truth", static_cast<int>(k), gt.frames[k]);
  }
  sr->stability_here = ms.data.sim && c.stability.enabled && *sr->setting == c.stability.setting &&
                       sr->size->name == c.stability.size;
}

// Training stage of a learned method: trains (or resumes) into its run folder, retrying from
// scratch when a resume fails; the row gets the training time and steps.
void TrainLearned(Measurement& ms, const SizeRuns& sr, const MethodSpec& m, int seed,
                  const std::string& run_dir, Clock::time_point t0, ResultRow* row) {
  const BenchRun& run = ms.run;
  const bool quiet = run.options.quiet;
  const model::P2iConfig mc = run.config.ModelConfig(m, *sr.size, seed);
  const std::string ckpt = model::Trainer::CheckpointPath(run_dir);
  model::TrainerOptions to;
  to.out_dir = run_dir;
  to.threads = run.threads;
  to.progress = !quiet && isatty(2);
  to.resume = fs::exists(ckpt);
  if (m.max_train_s > 0) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(m.max_train_s));
    to.should_stop = [deadline] { return Clock::now() >= deadline; };
  }
  if (!quiet)
    std::printf("[%zu/%zu] training %s (%s) on %s, %d frames at %dx%d, seed %d: %d + %d steps...\n",
                ms.done, ms.total, m.name.c_str(), mc.model.c_str(), sr.setting->Name().c_str(),
                row->train_frames, sr.size->resolution, sr.size->resolution, seed,
                mc.steps_phase1, mc.IsBaseline() || !mc.enet ? 0 : mc.steps_phase2);
  std::fflush(stdout);
  model::DensifyReport dr;
  const scene::RgbdDataset train = model::DensifyTrainingFrames(sr.train, mc, &dr);
  const std::string densified = model::DensifySummary(dr, mc);
  if (!densified.empty() && !quiet) std::printf("  %s\n", densified.c_str());
  model::TrainReport tr;
  try {
    tr = model::Trainer(mc, to).Run(train, scene::RgbdDataset{sr.train.camera, {}});
  } catch (const std::exception& e) {
    if (!to.resume) throw;
    std::fprintf(stderr, "resume of %s failed (%s): training from scratch\n", run_dir.c_str(),
                 e.what());
    fs::remove_all(run_dir);
    to.resume = false;
    tr = model::Trainer(mc, to).Run(train, scene::RgbdDataset{sr.train.camera, {}});
  }
  row->train_s = Since(t0);
  if (tr.stopped && !quiet)
    std::printf("  stopped by max_train_s = %.0f s after %d + %d steps\n", m.max_train_s,
                tr.phase1_steps, tr.phase2_steps);
  row->train_steps_phase1 = tr.phase1_steps;
  row->train_steps_phase2 = tr.phase2_steps;
}

// The method of one run: built from the training frames, or trained when its row or checkpoint
// is missing and loaded from the checkpoint.
std::unique_ptr<model::ViewSynthesizer> BuildMethod(Measurement& ms, const SizeRuns& sr,
                                                    const MethodSpec& m, int seed, bool have_row,
                                                    ResultRow* row) {
  const BenchRun& run = ms.run;
  const auto t0 = Clock::now();
  std::unique_ptr<model::ViewSynthesizer> synth;
  model::MethodInputs inputs;
  inputs.threads = run.threads;
  if (!m.IsLearned()) {
    inputs.training = std::make_shared<const scene::RgbdDataset>(sr.train);
    synth = m.make(inputs);
    row->train_s = Since(t0);  // index building
    return synth;
  }
  const std::string run_dir = (fs::path(run.out_dir) / "runs" / m.name / sr.setting->Name() /
                               sr.size->name / ("seed" + std::to_string(seed))).string();
  const std::string ckpt = model::Trainer::CheckpointPath(run_dir);
  if (!have_row || !fs::exists(ckpt)) TrainLearned(ms, sr, m, seed, run_dir, t0, row);
  inputs.checkpoint_path = ckpt;
  return m.make(inputs);
}

// Evaluation stage: the test views into the row, stored (results.csv/json rewritten) and printed.
void EvaluateRow(Measurement& ms, const SizeRuns& sr, const MethodSpec& m,
                 model::ViewSynthesizer& synth, ResultRow* row) {
  BenchRun& run = ms.run;
  Evaluate(synth, sr.test, run.lpips.get(), *sr.coverage, m.IsLearned() ? run.threads : 1, row);
  run.store.Add(*row);
  if (run.options.quiet) return;
  std::printf("[%zu/%zu] %s %s %s seed %d: PSNR %s dB, SSIM %s, LPIPS-Squeeze %s, "
              "AbsRel %s, pose-dependence %s, %s views/s (p50 %s ms, p99 %s ms), train %s s\n",
              ms.done, ms.total, m.name.c_str(), sr.setting->Name().c_str(),
              sr.size->name.c_str(), row->seed, Fixed(row->psnr).c_str(),
              Fixed(row->ssim, 3).c_str(), Fixed(row->lpips, 3).c_str(),
              Fixed(row->depth_abs_rel, 3).c_str(), Fixed(row->pose_dependence).c_str(),
              Fixed(row->views_per_s, 1).c_str(), Fixed(row->latency_p50_ms, 1).c_str(),
              Fixed(row->latency_p99_ms, 1).c_str(), Fixed(row->train_s, 0).c_str());
  const std::string warning = model::PoseDependenceWarning(row->pose_dependence);
  if (!warning.empty()) std::printf("  %s\n", warning.c_str());
  std::fflush(stdout);
}

// Strip stage of one method: its views at the strip poses.
void RenderStripViews(Measurement& ms, const SizeRuns& sr, const MethodSpec& m,
                      model::ViewSynthesizer& synth) {
  for (size_t k = 0; k < sr.strip_ids.size(); ++k) {
    const auto gt = ms.cache.Get({sr.strip_ids[k]}, *sr.size);
    SaveStripView(sr.strip_dir + "/" + m.name, static_cast<int>(k), synth.Render(gt.frames[0].pose));
  }
}

// Stability stage of one method: the sweep over the (shared) perturbed poses, saved at once.
void StabilityStage(Measurement& ms, SizeRuns& sr, const MethodSpec& m,
                    model::ViewSynthesizer& synth) {
  BenchRun& run = ms.run;
  if (!sr.stability_samples)
    sr.stability_samples = MakeStabilitySamples(run.config.stability, *ms.data.sim,
                                                sr.train.camera, sr.train_poses);
  const auto pts = RunStability(synth, m.name, *sr.stability_samples,
                                run.out_dir + "/stability_views.csv");
  run.stability.insert(run.stability.end(), pts.begin(), pts.end());
  SaveStability(run.out_dir, run.stability);
}

// The key fields of a row of `m` at the setting x size of `sr`.
ResultRow RowOf(const SizeRuns& sr, const MethodSpec& m, int seed) {
  ResultRow row;
  row.method = m.name;
  row.method_type = m.type;
  row.setting = sr.setting->Name();
  row.size = sr.size->name;
  row.resolution = sr.size->Width();
  row.height = sr.size->Height();
  row.seed = seed;
  row.train_frames = static_cast<int>(sr.train.frames.size());
  return row;
}

// One method x seed at a setting x size: what an earlier run left undone of its row, strip views
// and stability sweep.
void MeasureRun(Measurement& ms, SizeRuns& sr, const MethodSpec& m, int seed, bool first_seed) {
  BenchRun& run = ms.run;
  ResultRow row = RowOf(sr, m, seed);
  const bool have_row = run.store.Has(row.Key());
  const bool want_strip =
      sr.strip_size && first_seed && !fs::exists(sr.strip_dir + "/" + m.name + "/0_rgb.png");
  bool have_stab = false;
  for (const auto& p : run.stability) have_stab = have_stab || p.method == m.name;
  const bool want_stab = sr.stability_here && first_seed && !have_stab;
  if (have_row && !want_strip && !want_stab) return;

  const std::unique_ptr<model::ViewSynthesizer> synth = BuildMethod(ms, sr, m, seed, have_row, &row);
  if (!have_row) EvaluateRow(ms, sr, m, *synth, &row);
  if (want_strip) RenderStripViews(ms, sr, m, *synth);
  if (want_stab) StabilityStage(ms, sr, m, *synth);
}

// One ceiling row (eval/sim_ceiling.h) at a setting x size: the sim's own render at the test
// poses, evaluated as a method is.
void MeasureCeiling(Measurement& ms, const SizeRuns& sr, const std::string& kind) {
  BenchRun& run = ms.run;
  MethodSpec m;
  m.name = "ceiling_" + kind;
  m.type = "ceiling";
  ResultRow row = RowOf(sr, m, run.config.seeds.front());
  if (run.store.Has(row.Key())) return;
  SimCeilingView view(*ms.data.sim, kind, ms.data.index.camera(), sr.size->Width(), sr.size->Height(), sr.test);
  EvaluateRow(ms, sr, m, view, &row);
}

// One setting: its split saved, then every size that runs on it (strips at the first one).
void MeasureSetting(Measurement& ms, const scene::EvalSetting& setting, const scene::Split& split) {
  const BenchConfig& c = ms.run.config;
  const fs::path out_dir(ms.run.out_dir);
  split.ToYamlFile((out_dir / "splits" / (setting.Name() + ".yaml")).string());
  const auto test_ids = Subsample(split.test, static_cast<size_t>(c.max_test_views));
  const SizeSpec* strip_at = nullptr;  // strips at the first size that runs here
  for (const auto& size : c.sizes) {
    if (!AnyRunAt(c, setting, size)) continue;
    if (!strip_at) strip_at = &size;
    SizeRuns sr;
    sr.setting = &setting;
    sr.size = &size;
    sr.strip_ids = Subsample(test_ids, static_cast<size_t>(c.strip_views));
    sr.strip_dir = (out_dir / "strips" / setting.Name()).string();
    sr.strip_size = &size == strip_at && c.strip_views > 0;
    PrepareSize(ms, split, test_ids, &sr);
    for (const auto& m : c.methods) {
      const auto seeds = c.RunsOf(m, setting, size);
      for (int seed : seeds) {
        ++ms.done;
        MeasureRun(ms, sr, m, seed, seed == seeds.front());
      }
    }
    if (!ms.data.sim) continue;  // the config refuses `ceiling` without a sim scene
    for (const auto& kind : c.ceiling) {
      ++ms.done;
      MeasureCeiling(ms, sr, kind);
    }
  }
}

}  // namespace

BenchRun::BenchRun(BenchOptions o, BenchConfig c, std::string dir)
    : options(std::move(o)), config(std::move(c)), out_dir(std::move(dir)),
      store(out_dir, config.Hash()) {}

BenchRun StartBench(const BenchOptions& options) {
  BenchConfig c = BenchConfig::FromYamlFile(options.config_path);
  std::string out_dir =
      options.out_dir.empty()
          ? (fs::path("bench_out") / fs::path(options.config_path).stem()).string()
          : options.out_dir;
  BenchRun run(options, std::move(c), std::move(out_dir));
  run.threads = options.threads > 0 ? options.threads : run.config.threads;
  run.margin_db = options.auto_size_margin_db >= 0 ? options.auto_size_margin_db
                                                   : run.config.auto_size.margin_db;
  fs::create_directories(run.out_dir);
  run.started = UtcNow();
  run.load_start = LoadAverage();
  if (options.fresh) {
    for (const char* f :
         {"results.csv", "results.json", "stability.json", "stability.csv", "stability_views.csv"})
      fs::remove(fs::path(run.out_dir) / f);
    fs::remove_all(fs::path(run.out_dir) / "runs");
    fs::remove_all(fs::path(run.out_dir) / "strips");
  }
  const size_t resumed = run.store.LoadExisting();
  if (resumed > 0 && !options.quiet)
    std::printf("resuming: %zu row(s) already in %s\n", resumed, run.store.json_path().c_str());
  run.stability = LoadStability(run.out_dir);

  // LPIPS-Squeeze: reported as missing (never 0) when no weights are found.
  const std::string path = FindLpipsWeights(!options.lpips_weights.empty() ? options.lpips_weights
                                                                           : run.config.lpips_weights);
  std::string why;
  run.lpips = model::LpipsSqueeze::TryLoad(path, &why);
  run.lpips_status =
      run.lpips ? "weights " + run.lpips->weights_path()
                : "missing (" + (why.empty() ? std::string(model::kLpipsUnavailableMessage) : why) +
                      "; also looked at ../shared/models/lpips beside the checkout)";
  if (!run.lpips) std::fprintf(stderr, "warning: LPIPS-Squeeze %s\n", run.lpips_status.c_str());
  return run;
}

void RunMeasurements(BenchRun& run) {
  if (run.options.report_only) {
    if (!fs::exists(run.store.json_path()))
      throw std::runtime_error("--report-only: no " + run.store.json_path() + " to report on");
    return;
  }
  const BenchConfig& c = run.config;
  Measurement ms(run, PrepareData(c, run.out_dir, run.options.quiet));
  run.dataset = ms.data.description;
  fs::create_directories(fs::path(run.out_dir) / "splits");
  ms.total = CountRuns(c);
  // Every setting's split first: a setting the data cannot run fails before the first row.
  std::map<std::string, scene::Split> splits;
  for (const auto& setting : c.settings) splits[setting.Name()] = MakeSplit(c, ms.data.index, setting);
  for (const auto& setting : c.settings) MeasureSetting(ms, setting, splits.at(setting.Name()));
}

void ComposeStrips(BenchRun& run) {
  const BenchConfig& c = run.config;
  std::vector<std::string> strip_rows = {"ground_truth"};
  for (const auto& m : c.methods) strip_rows.push_back(m.name);
  if (c.strip_views <= 0) return;
  for (const auto& setting : c.settings) {
    const std::string name = setting.Name();
    const std::string dir = (fs::path(run.out_dir) / "strips" / name).string();
    const std::string png = (fs::path(run.out_dir) / "strips" / (name + ".png")).string();
    if (ComposeStrip(dir, strip_rows, c.strip_views, png))
      run.strips.emplace_back(name, "strips/" + name + ".png");
  }
}

ChartInputs MakeChartInputs(const BenchConfig& c, const std::vector<ResultRow>& rows,
                            const std::vector<StabilityPoint>& stability) {
  ChartInputs ci;
  ci.rows = rows;
  // Charts show the settings in the paper's order whatever the run order was.
  std::vector<scene::EvalSetting> ordered = c.settings;
  std::sort(ordered.begin(), ordered.end());
  for (const auto& s : ordered) ci.settings.push_back(s.Name());
  for (const auto& m : c.methods) ci.methods.push_back(m.name);
  for (const auto& s : c.sizes) ci.sizes.push_back(s.name);
  ci.primary_setting = c.auto_size.setting.Name();  // the setting with the ladder and the seeds
  ci.stability = stability;
  ci.threshold_db = c.stability.threshold_db;
  return ci;
}

void WriteBenchCharts(BenchRun& run) {
  run.chart_inputs = MakeChartInputs(run.config, run.store.rows(), run.stability);
  run.charts = WriteCharts(run.chart_inputs, (fs::path(run.out_dir) / "charts").string());
  if (!run.charts.note.empty()) std::fprintf(stderr, "note: %s\n", run.charts.note.c_str());
}

std::optional<LadderChoice> ChooseOnLadder(const BenchConfig& c, const std::vector<ResultRow>& rows,
                                           double margin_db) {
  if (c.sizes.size() <= 1 || c.auto_size.method.empty()) return std::nullopt;
  const std::string& method = c.auto_size.method;
  const std::string setting = c.auto_size.setting.Name();
  LadderChoice out;
  for (const auto& s : c.sizes) {
    SizeCandidate k;
    k.name = s.name;
    k.psnr_db = MeanOver(rows, method, setting, s.name, "psnr");
    k.params = MeanOver(rows, method, setting, s.name, "params");
    k.flops = MeanOver(rows, method, setting, s.name, "flops");
    k.views_per_s = MeanOver(rows, method, setting, s.name, "views_per_s");
    out.candidates.push_back(k);
  }
  out.choice = ChooseAutoSize(out.candidates, margin_db);
  const auto& cands = out.candidates;
  std::ostringstream os;
  os << "Ladder of `" << method << "` on setting " << setting << " (margin " << Fixed(margin_db)
     << " dB PSNR):\n\n| size | PSNR dB | params | GFLOP/view | views/s |\n|---|---|---|---|---|\n";
  for (size_t i = 0; i < cands.size(); ++i)
    os << "| " << (int(i) == out.choice.index ? "**" + cands[i].name + "**" : cands[i].name)
       << " | " << Fixed(cands[i].psnr_db) << " | " << Fixed(cands[i].params / 1e6, 3) << " M | "
       << Fixed(cands[i].flops / 1e9, 3) << " | " << Fixed(cands[i].views_per_s, 1) << " |\n";
  os << "\n--auto-size: " << out.choice.reason;
  out.markdown = os.str();
  return out;
}

std::vector<LadderChoice> ChooseAcrossMethods(const BenchConfig& c,
                                              const std::vector<ResultRow>& rows, double margin_db) {
  std::vector<LadderChoice> out;
  if (c.auto_size.methods.empty()) return out;
  const std::string setting = c.auto_size.setting.Name();
  for (const auto& s : c.sizes) {
    LadderChoice l;
    l.size = s.name;
    for (const std::string& method : c.auto_size.methods) {
      SizeCandidate k;
      k.name = method;
      k.psnr_db = MeanOver(rows, method, setting, s.name, "psnr");
      if (!std::isfinite(k.psnr_db)) continue;  // not run at this size (learned, non-square)
      k.params = MeanOver(rows, method, setting, s.name, "params");
      k.flops = MeanOver(rows, method, setting, s.name, "flops");
      k.views_per_s = MeanOver(rows, method, setting, s.name, "views_per_s");
      l.candidates.push_back(k);
    }
    if (l.candidates.size() < 2) continue;
    l.choice = ChooseAutoSize(l.candidates, margin_db, "method");
    std::ostringstream os;
    os << "Across methods at size `" << s.name << "` (" << s.Width() << "x" << s.Height()
       << ") on setting " << setting << " (margin " << Fixed(margin_db)
       << " dB PSNR):\n\n| method | PSNR dB | params | GFLOP/view | views/s |\n|---|---|---|---|---|\n";
    for (size_t i = 0; i < l.candidates.size(); ++i) {
      const SizeCandidate& k = l.candidates[i];
      os << "| " << (int(i) == l.choice.index ? "**" + k.name + "**" : k.name) << " | "
         << Fixed(k.psnr_db) << " | " << Fixed(k.params / 1e6, 3) << " M | "
         << Fixed(k.flops / 1e9, 3) << " | " << Fixed(k.views_per_s, 1) << " |\n";
    }
    os << "\n--auto-size: " << l.choice.reason;
    l.markdown = os.str();
    out.push_back(std::move(l));
  }
  return out;
}

void AutoSizeStage(BenchRun& run) {
  const BenchConfig& c = run.config;
  const std::optional<LadderChoice> ladder = ChooseOnLadder(c, run.store.rows(), run.margin_db);
  const std::vector<LadderChoice> across = ChooseAcrossMethods(c, run.store.rows(), run.margin_db);
  if (!ladder && across.empty()) {
    if (run.options.auto_size)
      std::printf("auto-size: needs at least 2 sizes and a learned method, or auto_size.methods "
                  "with 2 measured methods, in the config\n");
    return;
  }
  std::string text;
  if (ladder) {
    run.auto_size.push_back(ladder->markdown);
    text += ladder->choice.reason + "\n";
    if (run.options.auto_size)
      std::printf("auto-size (%s, setting %s): %s\n", c.auto_size.method.c_str(),
                  c.auto_size.setting.Name().c_str(), ladder->choice.reason.c_str());
  }
  for (const LadderChoice& l : across) {
    run.auto_size.push_back(l.markdown);
    text += l.choice.reason + "\n";
    if (run.options.auto_size)
      std::printf("auto-size across methods (size %s, setting %s): %s\n", l.size.c_str(),
                  c.auto_size.setting.Name().c_str(), l.choice.reason.c_str());
  }
  scene::WriteFileAtomic(run.out_dir + "/auto_size.txt", text);
}

ReportInputs MakeReportInputs(const BenchRun& run) {
  const BenchConfig& c = run.config;
  const BenchOptions& options = run.options;
  ReportInputs ri;
  ri.command = options.command_line.empty() ? "p2i bench " + options.config_path : options.command_line;
  ri.config_path = options.config_path;
  ri.dataset = !run.dataset.empty() ? run.dataset : "(report rebuilt from results.json)";
  errno = 0;
  const int nice_value = getpriority(PRIO_PROCESS, 0);
  ri.machine = std::to_string(std::thread::hardware_concurrency()) + " cores, load average " +
               run.load_start + " at start and " + LoadAverage() + " at the end (1/5/15 min); " +
               std::to_string(run.threads) +
               " LibTorch thread(s) for learned methods, baselines on 1; nice " +
               std::to_string(nice_value);
  ri.started = run.started;
  ri.finished = UtcNow();
  ri.lpips_status = run.lpips_status;
  ri.chart_inputs = run.chart_inputs;
  ri.charts = run.charts;
  ri.strips = run.strips;
  ri.auto_size = run.auto_size;
  if (!c.ceiling.empty())
    ri.notes.push_back("`ceiling_*` rows are not methods: the sim's own render at each test pose (`exact`: "
                       "pixel area only; `auto_exposure`: also the auto-exposure of the view's content; `colour`: "
                       "also the test frame's exposure and white-balance drifts), "
                       "scored against the test frames as the methods are. What separates "
                       "`ceiling_colour` from the test frames (RGB noise, motion blur) no view made "
                       "from a pose reproduces, nor the drifts (functions of time): `ceiling_colour` "
                       "bounds every method of the run, `ceiling_auto_exposure` every method that "
                       "cannot know the capture's time (eval/sim_ceiling.h).");
  for (const auto& m : c.methods) {
    if (!m.IsLearned()) continue;
    const auto mc = c.ModelConfig(m, c.sizes.front(), c.SeedsOf(m).front());
    ri.notes.push_back("`" + m.name + "` trained " + std::to_string(mc.steps_phase1) +
                       " phase-1 steps" +
                       (mc.IsBaseline() || !mc.enet
                            ? std::string("")
                            : " + " + std::to_string(mc.steps_phase2) + " ENET steps") +
                       " at batch " + std::to_string(mc.batch_size) +
                       " (the paper: tens of thousands)" +
                       (m.max_train_s > 0 ? ", each run capped at " + Fixed(m.max_train_s, 0) +
                                                " s (the steps column shows what ran)"
                                          : std::string("")) +
                       ": learned rows show an under-trained model when the budget is this small.");
  }
  return ri;
}

void WriteBenchReport(const BenchRun& run) {
  scene::WriteFileAtomic(run.out_dir + "/report.md", RenderReportMarkdown(MakeReportInputs(run)));
  if (!run.options.quiet)
    std::printf("wrote %s/results.csv, results.json, charts/, report.md (%zu rows)\n",
                run.out_dir.c_str(), run.store.rows().size());
}

std::vector<StabilitySample> MakeStabilitySamples(const StabilitySpec& spec,
                                                  const scene::SimScene& sim,
                                                  const scene::CameraInfo& camera,
                                                  const std::vector<scene::Pose>& train) {
  std::vector<StabilitySample> out;
  const model::CoverageScorer scorer(train);
  std::mt19937 rng(20261201);
  std::normal_distribution<double> n01;
  auto random_unit = [&]() {
    Eigen::Vector3d v(n01(rng), n01(rng), n01(rng));
    return v.norm() > 1e-9 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX();
  };
  const int n = std::min<int>(spec.poses, static_cast<int>(train.size()));
  for (int i = 0; i < n; ++i) {
    const size_t j = n == 1 ? 0 : static_cast<size_t>(i) * (train.size() - 1) / (n - 1);
    const scene::Pose& base = train[j];
    for (double d : spec.translations_m) {
      std::optional<scene::Pose> pose;
      for (int attempt = 0; attempt < 50 && !pose; ++attempt) {
        const Eigen::Vector3d t = base.translation() + d * random_unit();
        if (d == 0.0 || sim.IsFree(t, 0.1)) pose = scene::Pose(t, base.rotation());
      }
      if (!pose) continue;
      out.push_back({"translation", d, *pose, sim.Render(*pose, camera),
                     scorer.NearestDistance(*pose)});
    }
    for (double a : spec.rotations_deg) {
      const Eigen::Quaterniond q =
          base.rotation() * Eigen::Quaterniond(Eigen::AngleAxisd(a * M_PI / 180.0, random_unit()));
      const scene::Pose pose(base.translation(), q);
      out.push_back({"rotation", a, pose, sim.Render(pose, camera), scorer.NearestDistance(pose)});
    }
  }
  return out;
}

}  // namespace p2i::eval
