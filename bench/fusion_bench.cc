/// @file fusion_bench.cc
/// @brief Speed and memory of the `fusion` method (issue 12's speed targets): TSDF integration
/// time per camera frame (against a 30 Hz camera's 33.3 ms) with blocks of 16^3 and 8^3 voxels,
/// and into the fused scene with its default options (blocks auto: 8^3 for these 640x480 frames)
/// without and with submaps; render time per view at 128x128 and 320x240 with the default surface
/// (the TSDF's mesh, bicubic keyframe reads), with bilinear reads, with the raycast (hit refinement
/// on and off), with 16^3 blocks, with submaps and alignment, study_room.yaml's configuration for
/// real poses (row fusion_real) and with the learned refinement, and the fused scene's memory per
/// m^3 of allocated blocks. The method is built through the method registry,
/// as `p2i bench` and the synthesizer build it; transport is not included (pipeline_bench has
/// it). Then where a view's time goes (raycast, hit refinement, crack fill, or the mesh's z-buffer;
/// keyframe blend), with the time to prepare the surface after the last frame (mesh extraction). Prints
/// tables and writes JSON.
///
/// Usage: OMP_NUM_THREADS=1 fusion_bench [--scene small_office] [--frames 40] [--views 30]
///                                       [--net models/refine_sim.pt] [--json fusion_bench.json]
///                                       [--stages-only] [--row LABEL [--repeat N]] [--size WxH]
/// (--size: rows and stages at this size only; --row: one render row, nothing else, each
/// test pose rendered N times: for a
/// profiler, e.g. `perf record build/bin/fusion_bench --row submaps_20 --repeat 20`)
/// OMP_NUM_THREADS=1 makes Open3D's kernels and LibTorch use one thread (both read it at start).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "fusion/fusion_synthesizer.h"
#include "fusion/tsdf_volume.h"
#include "model/method_registry.h"
#include "model/metrics.h"
#include "scene/image_ops.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "util/heap_policy.h"
#include "util/order_stats.h"

namespace {

using p2i::util::Median;

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

struct Args {
  std::string scene = "small_office";
  int frames = 40;  ///< training frames (every 4th pose of the first sweep) at 640x480
  int views = 30;   ///< test poses on the adjacent sweep
  std::string net;  ///< refinement file ("" = no refined rows)
  std::string json = "fusion_bench.json";
  bool stages_only = false;  ///< only the stage breakdown (for a profiler)
  std::string row;           ///< only this render row (both sizes), no integration or stages
  int repeat = 1;            ///< renders of each test pose per row (a profiler wants many)
  int width = 0, height = 0; ///< --size WxH: render rows at this size only (0: 128x128 and 320x240)
};

bool ParseArgs(int argc, char** argv, Args* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    const bool has = i + 1 < argc;
    if (k == "--scene" && has) {
      a->scene = argv[++i];
    } else if (k == "--frames" && has) {
      a->frames = std::max(2, std::atoi(argv[++i]));
    } else if (k == "--views" && has) {
      a->views = std::max(1, std::atoi(argv[++i]));
    } else if (k == "--net" && has) {
      a->net = argv[++i];
    } else if (k == "--json" && has) {
      a->json = argv[++i];
    } else if (k == "--row" && has) {
      a->row = argv[++i];
    } else if (k == "--repeat" && has) {
      a->repeat = std::max(1, std::atoi(argv[++i]));
    } else if (k == "--size" && has) {
      if (std::sscanf(argv[++i], "%dx%d", &a->width, &a->height) != 2 || a->width < 8 || a->height < 8) {
        std::cerr << "fusion_bench: --size " << argv[i] << ": expected WxH, e.g. 128x128 (each >= 8)\n";
        return false;
      }
    } else if (k == "--stages-only") {
      a->stages_only = true;
    } else {
      return false;
    }
  }
  return true;
}

/// The training frames (640x480, the first of three adjacent sweeps) and the test poses (the
/// second sweep), as in the bench's setting (b).
void MakeData(const Args& a, const p2i::scene::SimScene& sim, p2i::scene::RgbdDataset* train,
              std::vector<p2i::scene::Pose>* test) {
  const auto sweeps = p2i::scene::GenerateAdjacentSweeps(p2i::scene::AdjacentSweepsOptions{});
  train->camera = p2i::scene::SimScene::DefaultCamera(640, 480);
  const auto& first = sweeps[0];
  const size_t step = std::max<size_t>(1, first.size() / static_cast<size_t>(a.frames));
  for (size_t i = 0; i < first.size() && static_cast<int>(train->frames.size()) < a.frames; i += step)
    train->frames.push_back(sim.Render(first[i].pose, train->camera, first[i].stamp));
  const auto& second = sweeps[1];
  const size_t vstep = std::max<size_t>(1, second.size() / static_cast<size_t>(a.views));
  for (size_t i = vstep / 2; i < second.size() && static_cast<int>(test->size()) < a.views; i += vstep)
    test->push_back(second[i].pose);
}

/// Median time of `integrate(frame)` over the training frames, in order (ms); the slowest frame's
/// time in `worst_ms` when given (the frame whose blocks made the hash map double).
template <typename Integrate>
double MedianIntegrationMs(const p2i::scene::RgbdDataset& train, Integrate integrate,
                           double* worst_ms = nullptr) {
  std::vector<double> ms;
  for (const auto& f : train.frames) {
    const auto t0 = Clock::now();
    integrate(f);
    ms.push_back(Ms(t0, Clock::now()));
  }
  if (worst_ms) *worst_ms = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  return Median(ms);
}

/// Median integration time of each training frame into a fresh TSDF (2 cm voxels, blocks of
/// `block_resolution`^3), and the volume's memory afterwards.
nlohmann::json BenchIntegration(const p2i::scene::RgbdDataset& train, int block_resolution) {
  p2i::fusion::TsdfOptions options;
  options.block_resolution = block_resolution;
  p2i::fusion::TsdfVolume tsdf(options);
  double worst = 0.0;
  const double p50 = MedianIntegrationMs(
      train, [&](const p2i::scene::RgbdSample& f) { tsdf.Integrate(f, train.camera); }, &worst);
  const p2i::fusion::TsdfStats s = tsdf.Stats();
  const bool keeps_up = p50 < 1000.0 / 30.0;
  nlohmann::json j;
  j["frame_size"] = std::to_string(train.camera.image_width) + "x" + std::to_string(train.camera.image_height);
  j["block_resolution"] = block_resolution;
  j["frames"] = train.frames.size();
  j["integrate_ms_p50"] = p50;
  j["keeps_up_with_30hz"] = keeps_up;
  j["integrate_ms_max"] = worst;
  j["blocks"] = s.blocks;
  j["capacity_blocks"] = s.capacity_blocks;
  j["memory_mb"] = s.memory_bytes / 1e6;
  // What the process holds: Open3D allocates and touches the voxel data of every block the hash
  // map has room for.
  j["reserved_mb"] = s.blocks > 0 ? s.memory_bytes / 1e6 * static_cast<double>(s.capacity_blocks) /
                                        static_cast<double>(s.blocks)
                                  : 0.0;
  j["block_volume_m3"] = s.block_volume_m3;
  j["memory_mb_per_m3"] = s.block_volume_m3 > 0 ? s.memory_bytes / 1e6 / s.block_volume_m3 : 0.0;
  std::printf("integration (%s, %zu frames, blocks of %d^3 voxels): p50 %.1f ms/frame (30 Hz "
              "budget 33.3 ms: %s), slowest frame %.0f ms (the hash map doubles as blocks fill it)\n",
              j["frame_size"].get<std::string>().c_str(), train.frames.size(), block_resolution, p50,
              keeps_up ? "keeps up" : "falls behind", worst);
  std::printf("memory: %lld blocks, %.1f MB over %.2f m^3 of blocks = %.1f MB per m^3; room for %lld "
              "blocks = %.1f MB held\n",
              static_cast<long long>(s.blocks), s.memory_bytes / 1e6, s.block_volume_m3,
              j["memory_mb_per_m3"].get<double>(), static_cast<long long>(s.capacity_blocks),
              j["reserved_mb"].get<double>());
  // The one-time copy a fused scene makes of its global TSDF when a second capture starts (its
  // per-capture submaps, the default: SubmapSet::Integrate), median of three.
  std::vector<double> clone_ms;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = Clock::now();
    const p2i::fusion::TsdfVolume copy = tsdf.Clone();
    clone_ms.push_back(Ms(t0, Clock::now()));
  }
  j["clone_ms_p50"] = Median(clone_ms);
  std::printf("copy for a second capture's submaps (once, at its first frame): %.1f ms\n",
              j["clone_ms_p50"].get<double>());
  return j;
}

/// Median time to integrate each training frame into a fresh FusionScene with the default options
/// (block size auto) and `submaps` frames per local submap (0 = one global TSDF), as the trainer's
/// mapper integrates a camera frame: the global TSDF plus, with submaps, the current submap (each
/// frame goes into both).
nlohmann::json BenchSceneIntegration(const p2i::scene::RgbdDataset& train, int submaps) {
  p2i::fusion::FusionSceneOptions options;
  options.submaps.frames = submaps;
  options.submaps.use = "always";
  p2i::fusion::FusionScene scene(train.camera, options);
  const int blocks = scene.options().tsdf.block_resolution;
  double worst = 0.0;
  const double p50 =
      MedianIntegrationMs(train, [&](const p2i::scene::RgbdSample& f) { scene.Integrate(f); }, &worst);
  nlohmann::json j;
  j["submap_frames"] = submaps;
  j["block_resolution"] = blocks;
  j["frames"] = train.frames.size();
  j["integrate_ms_p50"] = p50;
  j["keeps_up_with_30hz"] = p50 < 1000.0 / 30.0;
  j["integrate_ms_max"] = worst;
  std::printf("integration into the fused scene (default options: blocks auto = %d^3, %s): p50 %.1f "
              "ms/frame (30 Hz budget 33.3 ms: %s), slowest frame %.0f ms\n",
              blocks, submaps > 0 ? ("submaps of " + std::to_string(submaps) + " frames").c_str() : "no submaps",
              p50, p50 < 1000.0 / 30.0 ? "keeps up" : "falls behind", worst);
  return j;
}

/// The ground truth of the rows' quality columns: what the camera would deliver at each test
/// pose (`frames`: the sim's exact render at the frames' 640x480), resized to w x h as the camera
/// node resizes its frames (centre crop + area resize). The sim's own render at w x h would not
/// do: it samples its textures at pixel centres, unfiltered, which no camera does.
std::vector<p2i::scene::RgbdSample> GroundTruth(const std::vector<p2i::scene::RgbdSample>& frames, int w,
                                                int h) {
  std::vector<p2i::scene::RgbdSample> gt;
  for (const auto& f : frames) gt.push_back(p2i::scene::CenterCropResizeSample(f, w, h));
  return gt;
}

/// One row: the method built from `options` over `train`, its median render time over the test
/// poses and its mean PSNR / SSIM against `gt`. The frames are resized to the view's w x h first,
/// as `p2i bench` does, or (`live`) kept at the camera's 640x480, as the trainer's fusion mapper
/// keeps its keyframes, with the views rendered at w x h from them.
nlohmann::json BenchRender(const std::string& label, const std::string& options, bool live,
                           const p2i::scene::RgbdDataset& train, const std::vector<p2i::scene::Pose>& test,
                           const std::vector<p2i::scene::RgbdSample>& gt, int w, int h, int repeat) {
  const auto t0 = Clock::now();
  std::unique_ptr<p2i::model::ViewSynthesizer> synth;
  if (live) {
    synth = std::make_unique<p2i::fusion::FusionSynthesizer>(
        train, p2i::fusion::FusionOptions::FromYaml(YAML::Load(options), "fusion_bench"),
        p2i::scene::CenterCropResizeCamera(train.camera, w, h));
  } else {
    p2i::model::MethodInputs in;
    in.training = std::make_shared<p2i::scene::RgbdDataset>(p2i::scene::CenterCropResizeDataset(train, w, h));
    synth = p2i::model::GetMethod("fusion").configure(YAML::Load(options), "fusion_bench")(in);
  }
  const double build_ms = Ms(t0, Clock::now());
  synth->Render(test.front());  // warm-up (first allocations, LibTorch's first call)
  std::vector<double> ms;
  double observed = 0.0, psnr = 0.0, ssim = 0.0;
  for (int r = 0; r < repeat; ++r)
    for (size_t i = 0; i < test.size(); ++i) {
      const auto a = Clock::now();
      const p2i::scene::RgbdSample view = synth->Render(test[i]);
      ms.push_back(Ms(a, Clock::now()));
      const auto g = synth->LastGeometry();
      if (!g.empty()) observed += g.front().observed_fraction / repeat;
      if (r == 0) {
        psnr += p2i::model::Psnr(view.rgb, gt[i].rgb) / test.size();
        ssim += p2i::model::Ssim(view.rgb, gt[i].rgb) / test.size();
      }
    }
  const double p50 = Median(ms);
  const double p99 = p2i::util::PercentileNearestRank(ms, 99.0);
  std::printf("%-26s %4dx%-4d %9.1f %9.1f %9.1f %10.0f %9.3f %7.2f %6.3f\n", label.c_str(), w, h, p50, p99,
              p50 > 0 ? 1000.0 / p50 : 0.0, build_ms, observed / test.size(), psnr, ssim);
  nlohmann::json j;
  j["live"] = live;
  j["psnr_db"] = psnr;
  j["ssim"] = ssim;
  j["row"] = label;
  j["width"] = w;
  j["height"] = h;
  j["options"] = options;
  j["render_ms_p50"] = p50;
  j["render_ms_p99"] = p99;
  j["views_per_s"] = p50 > 0 ? 1000.0 / p50 : 0.0;
  j["build_ms"] = build_ms;
  j["observed_fraction_mean"] = observed / test.size();
  return j;
}

/// Where a view's time goes, at w x h on a FusionScene of the same frames (default options):
/// Open3D's raycast alone, + the trilinear hit refinement, + the crack fill (the default raycast),
/// then the raycast + keyframe blend (RenderCandidates), the mesh's z-buffer and the mesh + blend,
/// and the last two again over keyframes kept at 640x480 (`live`, as the trainer's mapper keeps
/// them). The full Render row adds the conversion to an 8-bit view and the hole fill (or the
/// learned refinement).
nlohmann::json BenchStages(const p2i::scene::RgbdDataset& train, const std::vector<p2i::scene::Pose>& test,
                           int w, int h) {
  const p2i::scene::RgbdDataset frames = p2i::scene::CenterCropResizeDataset(train, w, h);
  const p2i::scene::CameraInfo view_camera = frames.camera;
  struct Stage { std::string label; bool refine; int cracks; bool blend; std::string surface; bool live = false; };
  const std::vector<Stage> stages = {{"open3d raycast", false, 0, false, "raycast"},
                                     {"+ hit refinement", true, 0, false, "raycast"},
                                     {"+ crack fill", true, 2, false, "raycast"},
                                     {"+ keyframe blend", true, 2, true, "raycast"},
                                     {"mesh raster", true, 2, false, "mesh"},
                                     {"mesh + keyframe blend", true, 2, true, "mesh"},
                                     {"live mesh raster", true, 2, false, "mesh", true},
                                     {"live mesh + keyframe blend", true, 2, true, "mesh", true}};
  nlohmann::json out = nlohmann::json::object();
  for (const Stage& st : stages) {
    p2i::fusion::FusionSceneOptions o;
    o.tsdf.refine_hits = st.refine;
    o.tsdf.crack_fill_passes = st.cracks;
    o.tsdf.surface = st.surface;
    // live: keyframes kept at the camera's 640x480, as the trainer's mapper keeps them.
    const p2i::scene::RgbdDataset& fused = st.live ? train : frames;
    p2i::fusion::FusionScene scene(fused.camera, o);
    for (const auto& f : fused.frames) scene.AddFrame(f);
    const auto p0 = Clock::now();
    scene.tsdf().Prepare();  // the mesh of surface "mesh" (once per change of the volume)
    const double prepare_ms = Ms(p0, Clock::now());
    auto once = [&](const p2i::scene::Pose& pose) {
      if (st.blend) scene.RenderCandidates(pose, view_camera);
      else scene.tsdf().Raycast(pose, view_camera);
    };
    once(test.front());
    std::vector<double> ms;
    for (const auto& pose : test) {
      const auto a = Clock::now();
      once(pose);
      ms.push_back(Ms(a, Clock::now()));
    }
    const double p50 = Median(ms);
    std::printf("  stage %-22s %4dx%-4d %9.1f ms   (prepare %.0f ms)\n", st.label.c_str(), w, h, p50,
                prepare_ms);
    out[st.label] = p50;
    out["prepare_ms " + st.label] = prepare_ms;
  }
  return out;
}

/// One render row: fusion options (YAML) under a label; live rows keep the keyframes at 640x480 as
/// the trainer's mapper keeps them (BenchRender).
struct Row {
  std::string label, options;
  bool live = false;
};

/// The render rows, with the refined row when --net is given, or only the --row one.
std::vector<Row> RenderRows(const Args& a) {
  std::vector<Row> rows = {{"blend (mesh)", "{}"},
                           {"blend_bilinear", "{blend: {sampling: bilinear}}"},
                           {"blend_catmull_rom", "{blend: {cubic_a: -0.5}}"},  // the bicubic before session 50
                           {"blend_raycast", "{tsdf: {surface: raycast}}"},
                           {"blend_raycast_no_refine", "{tsdf: {surface: raycast, refine_hits: false}}"},
                           {"blend_block16", "{tsdf: {block_resolution: 16}}"},
                           {"submaps_10", "{submaps: {frames: 10}}"},
                           {"submaps_10_render1", "{submaps: {frames: 10, render: 1}}"},
                           {"submaps_20", "{submaps: {frames: 20}}"},
                           {"submaps_20_render1", "{submaps: {frames: 20, render: 1}}"},
                           {"align_1", "{blend: {align_iterations: 1}}"},
                           {"align_1_fast", "{blend: {align_iterations: 1, align_flow_preset: fast}}"},
                           {"align_1_ultrafast", "{blend: {align_iterations: 1, align_flow_preset: ultrafast}}"},
                           {"align_2", "{blend: {align_iterations: 2}}"},
                           {"submaps_20_align_1", "{submaps: {frames: 20}, blend: {align_iterations: 1}}"},
                           // study_room.yaml's fusion_real: the configuration for real poses
                           {"fusion_real", "{submaps: {frames: 20}, blend: {align_iterations: 1, depth: keyframes}}"},
                           // the same with alignment and depth chosen from the keyframes (both off on the sim)
                           {"fusion_real_auto", "{submaps: {frames: 20}, blend: {align_iterations: auto, depth: auto}}"},
                           {"live_blend", "{}", true},
                           {"live_blend_full_res_reads", "{blend: {keyframe_levels: 0}}", true},
                           {"live_blend_bicubic", "{blend: {sampling: bicubic}}", true}};
  if (!a.net.empty()) rows.push_back({"refined (zero-shot)", "{refine: {net: '" + a.net + "'}}"});
  if (a.row.empty()) return rows;
  const auto it = std::find_if(rows.begin(), rows.end(), [&](const Row& r) { return r.label == a.row; });
  if (it == rows.end()) throw std::runtime_error("--row " + a.row + ": no such row (see the table's first column)");
  return {*it};
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("fusion_bench")) return 2;  // P2I_HEAP
  Args a;
  if (!ParseArgs(argc, argv, &a)) {
    std::cerr << "usage: OMP_NUM_THREADS=1 fusion_bench [--scene NAME] [--frames N] [--views N] "
                 "[--net FILE] [--json FILE] [--stages-only] [--row LABEL [--repeat N]] [--size WxH]\n";
    return 2;
  }
  try {
    const char* omp = std::getenv("OMP_NUM_THREADS");
    std::printf("fusion_bench: scene %s, %d training frames, %d views, OMP_NUM_THREADS=%s\n",
                a.scene.c_str(), a.frames, a.views, omp ? omp : "(unset: all cores)");
    const auto sim = p2i::scene::SimScene::BuiltIn(a.scene);
    p2i::scene::RgbdDataset train;
    std::vector<p2i::scene::Pose> test;
    MakeData(a, sim, &train, &test);
    nlohmann::json out;
    out["scene"] = a.scene;
    out["omp_num_threads"] = omp ? omp : "";
    std::vector<std::pair<int, int>> sizes = {{128, 128}, {320, 240}};
    if (a.width > 0) sizes = {{a.width, a.height}};
    if (!a.stages_only) {
      if (a.row.empty()) {
        out["integration"] = BenchIntegration(train, 16);  // block_resolution auto for coarse frames
        out["integration_block8"] = BenchIntegration(train, 8);
        out["integration_scene"] = BenchSceneIntegration(train, 0);
        out["integration_scene_submaps_20"] = BenchSceneIntegration(train, 20);
      }
      std::printf("%-26s %9s %9s %9s %9s %10s %9s %7s %6s\n", "row", "size", "p50_ms", "p99_ms", "views/s",
                  "build_ms", "observed", "psnr", "ssim");
      const std::vector<Row> rows = RenderRows(a);
      std::vector<p2i::scene::RgbdSample> test_frames;  // at the camera's 640x480, once
      for (const auto& pose : test) test_frames.push_back(sim.Render(pose, train.camera, 0.0));
      for (const auto& size : sizes) {
        const auto gt = GroundTruth(test_frames, size.first, size.second);
        for (const Row& r : rows)
          out["render"].push_back(
              BenchRender(r.label, r.options, r.live, train, test, gt, size.first, size.second, a.repeat));
      }
    }
    if (a.row.empty()) {
      std::printf("stages (median ms per view, cumulative):\n");
      for (const auto& size : sizes)
        out["stages_ms_p50"][std::to_string(size.first) + "x" + std::to_string(size.second)] =
            BenchStages(train, test, size.first, size.second);
    }
    std::ofstream(a.json) << out.dump(2) << "\n";
    std::printf("wrote %s\n", a.json.c_str());
  } catch (const std::exception& e) {
    std::cerr << "fusion_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
