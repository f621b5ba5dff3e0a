/// @file bench_config.h
/// @brief The YAML configuration of `p2i bench` (docs/EVALUATION.md, bench/configs/*.yaml):
/// dataset, settings, methods, sizes, seeds, threads, stability sweep, strips, auto-size.
#pragma once

#include <string>
#include <vector>

#include "model/method_registry.h"
#include "model/p2i_config.h"
#include "scene/sim_sensor_options.h"
#include "scene/splits.h"

namespace p2i::eval {

/// Where the frames come from.
struct DatasetSpec {
  /// A sim scene rendered on the fly (SimScene::FromSpec: builtin:NAME, NAME or a scene YAML),
  /// along `trajectories` adjacent arm sweeps (seq-01, seq-02, ...). Exclusive with `path`.
  std::string scene;
  /// A dataset folder: p2i capture, TUM RGB-D or 7-Scenes (scene::OpenDataset).
  std::string path;
  std::string format = "auto";
  int seven_scenes_invalid_depth = 65535;
  /// path: the sequences kept, by name (e.g. {"seq-01"}; empty = all). A name the folder does
  /// not hold is an error listing the names it does.
  std::vector<std::string> sequences;
  int trajectories = 3;             ///< scene: number of adjacent arm sweeps
  double trajectory_offset = 0.1;   ///< scene: metres between neighbouring sweeps (radial)
  std::vector<double> heights = {1.0, 1.3, 1.6};  ///< scene: arm sweep heights (m)
  double speed = 0.15;              ///< scene: camera speed (m/s) at 20 frames/s
  int max_frames = 0;               ///< frames per sequence kept (0 = all), after frame_step
  int frame_step = 1;               ///< keep every k-th frame
  int render_size = 0;              ///< scene: square render side (0 = largest size resolution)
  /// scene: the sensor model the frames are rendered with (default: none, the exact render;
  /// the shipped configs use {preset: realistic}: docs/SCENE.md)
  scene::SimSensorOptions sensor;
  bool specular = true;  ///< scene: false renders view-dependent materials Lambertian
  bool IsSim() const { return !scene.empty(); }
};

/// One method row of the tables.
struct MethodSpec {
  std::string name;      ///< unique; the row label
  std::string type;      ///< a canonical name of model/method_registry.h (aliases resolved)
  bool learned = false;  ///< model::MethodInfo::learned of `type`
  std::string preset;    ///< learned: preset file resolved to a path
  std::string config_yaml;  ///< learned: P2iConfig overrides of this method (YAML map text)
  int steps = -1;        ///< learned: phase-1 steps (-1 = the preset's)
  int enet_steps = -1;   ///< p2i: phase-2 (ENET) steps (-1 = max(1, steps / 4) or the preset's)
  int batch_size = -1;   ///< learned: batch size (-1 = the preset's)
  /// learned: wall-time cap of one training run in seconds (0 = none). Training stops at the next
  /// step boundary (TrainerOptions::should_stop); the row reports the steps actually run.
  double max_train_s = 0.0;
  std::vector<int> seeds;   ///< learned: overrides the global seeds (e.g. 3 seeds for P2I-NET)
  /// Settings on which all seeds run; elsewhere only the first seed (empty = every setting).
  std::vector<scene::EvalSetting> seed_settings;
  /// Sizes at which all seeds run; elsewhere only the first seed (empty = every size).
  std::vector<std::string> seed_sizes;
  /// The method's own options (the entry's keys listed in MethodInfo::option_keys, e.g. warp's
  /// k and fill_holes) as a YAML map text, "" for none; checked when the config is read.
  std::string options_yaml;
  /// The method configured with those options (MethodInfo::configure), set by FromYamlString.
  model::MethodFactory make;
  bool IsLearned() const { return learned; }
};

/// One rung of the size ladder: a resolution and P2iConfig overrides for learned methods.
struct SizeSpec {
  std::string name;
  int resolution = 128;  ///< view width (and height when `height` is 0)
  /// View height, 0 = square. A non-square size (e.g. 320 x 240, the camera's 4:3) runs the
  /// methods that are not learned; learned methods (square networks) skip it.
  int height = 0;
  int Width() const { return resolution; }
  int Height() const { return height > 0 ? height : resolution; }
  bool Square() const { return Height() == Width(); }
  std::string model_yaml;  ///< P2iConfig overrides (YAML map text), may be empty
  std::vector<scene::EvalSetting> settings;  ///< run only on these settings (empty = every one)
};

struct StabilitySpec {
  bool enabled = true;  ///< only possible on a sim scene (exact ground truth anywhere)
  std::vector<double> translations_m = {0.0, 0.05, 0.1, 0.2, 0.4, 0.8};
  std::vector<double> rotations_deg = {0.0, 2.5, 5.0, 10.0, 20.0, 40.0};
  int poses = 8;               ///< training poses the offsets start from
  double threshold_db = 20.0;  ///< "falls below X dB at distance D"
  scene::EvalSetting setting;  ///< the trained models of this setting (default: the first)
  std::string size;            ///< ... of this size (default: the first)
};

struct AutoSizeSpec {
  std::string method;     ///< the size ladder of this method; default: the first learned method
  /// Across methods: at each size, the cheapest of these methods within the margin of their best
  /// PSNR (e.g. warp, fusion variants with other voxel sizes or refinement nets, p2i). Empty =
  /// no choice across methods.
  std::vector<std::string> methods;
  scene::EvalSetting setting;  ///< default: the first setting
  double margin_db = 0.5;
};

struct BenchConfig {
  std::string source;  ///< the file it was read from
  std::string text;    ///< its text (hashed to recognise a resumable output folder)
  DatasetSpec dataset;
  std::vector<scene::EvalSetting> settings;  ///< a1 a3 a10 a20 (setting a, N held out) b c
  int period = 100;                    ///< setting (a): frames per block
  std::string b_train, b_test;         ///< setting (b) sequences (default: first two)
  std::vector<std::string> c_train, c_test;  ///< setting (c) (default: middle one tests)
  int max_test_views = 50;             ///< test frames evaluated per setting (evenly spaced)
  std::vector<MethodSpec> methods;
  std::vector<SizeSpec> sizes;
  std::vector<int> seeds = {1};
  int threads = 1;
  std::string lpips_weights;  ///< optional path (else --lpips-weights, P2I_LPIPS_WEIGHTS, ../shared)
  int strip_views = 4;        ///< poses per image strip in the report
  StabilitySpec stability;
  AutoSizeSpec auto_size;
  /// Sim scenes only: ceiling rows (eval/sim_ceiling.h), each kind ("exact", "auto_exposure",
  /// "colour") a row
  /// `ceiling_KIND` at every setting and size: the scene's own render at the test poses, scored
  /// as the methods are. Empty (the default) = none.
  std::vector<std::string> ceiling;

  /// Strict: unknown keys, bad values and unknown presets throw std::runtime_error naming the
  /// file, the line and the key. Every learned (method, size) model config is built once here so
  /// that a bad override stops the run at start-up.
  static BenchConfig FromYamlString(const std::string& text, const std::string& source);
  static BenchConfig FromYamlFile(const std::string& path);

  /// The P2iConfig of a learned method at a size and seed: preset, then size overrides, then the
  /// method's overrides, then resolution, steps, batch size and seed.
  model::P2iConfig ModelConfig(const MethodSpec& method, const SizeSpec& size, int seed) const;
  std::vector<int> SeedsOf(const MethodSpec& method) const;
  /// The seeds of `method` at (setting, size); empty when the combination is not run (the size
  /// is restricted to other settings, or a non-learned method already ran at an earlier size of
  /// the same resolution: baselines do not depend on the model overrides).
  std::vector<int> RunsOf(const MethodSpec& method, const scene::EvalSetting& setting,
                          const SizeSpec& size) const;
  const MethodSpec* FindMethod(const std::string& name) const;
  const SizeSpec* FindSize(const std::string& name) const;
  /// FNV-1a of the text, hex.
  std::string Hash() const;
};

/// Resolves a preset name ("default" -> <source>/model/presets/default.yaml) or a path relative
/// to `config_dir`. Throws std::runtime_error listing where it looked.
std::string ResolvePreset(const std::string& preset, const std::string& config_dir);

}  // namespace p2i::eval
