/// @file cmd_render.cc
/// @brief `p2i render`: writes p2i capture datasets rendered from the synthetic scene.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include "scene/capture.h"
#include "scene/dataset_trajectories.h"
#include "scene/sim_scene.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

// --kinect or --sensor (a preset name or an inline YAML map) on the sim scene.
void SetSensor(bool kinect, const std::string& sensor, scene::SimScene* sim) {
  if (kinect && !sensor.empty()) throw std::invalid_argument("give --kinect or --sensor, not both");
  if (kinect) sim->set_sensor_options(scene::SimSensorOptions::Kinect());
  if (sensor.empty()) return;
  const std::string text = sensor.find('{') == std::string::npos ? "{preset: " + sensor + "}" : sensor;
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("--sensor '" + sensor + "': not a preset name or a YAML map (" +
                                e.msg + ")");
  }
  sim->set_sensor_options(scene::SimSensorOptions::FromYaml(node, "--sensor"));
}

// --camera scaled to --width/--height, else the default camera at that size (0 = 640x480).
scene::CameraInfo RenderCamera(const std::string& camera_file, int width, int height) {
  scene::CameraInfo camera;
  if (!camera_file.empty()) {
    camera = scene::CameraInfo::FromYamlFile(camera_file);
    if ((width > 0 || height > 0) &&
        (width != camera.image_width || height != camera.image_height)) {
      camera = camera.Scaled(width > 0 ? width : camera.image_width,
                             height > 0 ? height : camera.image_height);
    }
  } else {
    // Kinect-like 58 degree horizontal field of view at any size, square pixels.
    camera = scene::SimScene::DefaultCamera(width > 0 ? width : 640, height > 0 ? height : 480);
  }
  camera.Validate();
  return camera;
}

// Each trajectory (cut to max_frames, restamped at fps unless 0) into OUT/seq-NN; returns the
// frame count.
size_t RenderSequences(const scene::SimScene& sim, const scene::CameraInfo& camera,
                       std::vector<std::vector<scene::StampedPose>>* all, int max_frames,
                       double fps, const std::string& out_dir, bool overwrite) {
  size_t total = 0;
  for (size_t k = 0; k < all->size(); ++k) {
    auto& traj = (*all)[k];
    if (max_frames > 0 && traj.size() > static_cast<size_t>(max_frames)) traj.resize(max_frames);
    if (fps > 0.0) scene::Restamp(&traj, fps);
    char name[32];
    std::snprintf(name, sizeof(name), "seq-%02zu", k + 1);
    const std::string dir = (std::filesystem::path(out_dir) / name).string();
    scene::CaptureWriter::Options options;
    options.overwrite = overwrite;
    scene::CaptureWriter writer(dir, camera, options);
    for (std::size_t i = 0; i < traj.size(); ++i) {
      writer.Append(sim.RenderOnTrajectory(traj, i, camera));  // motion blur along it, if on
    }
    total += traj.size();
    std::printf("%s: %zu frames\n", dir.c_str(), traj.size());
  }
  return total;
}

int RunRender(const std::vector<std::string>& args) {
  CLI::App app{"Render p2i capture datasets (one seq-NN folder per trajectory) from the "
               "synthetic scene. See docs/DATASETS.md.",
               "p2i render"};
  std::string scene_spec;
  std::vector<std::string> trajectories;
  std::string out_dir;
  int width = 0, height = 0;
  std::string camera_file;
  double fps = 20.0;
  int max_frames = 0;
  bool kinect = false;
  std::string sensor;
  bool overwrite = false;
  app.add_option("scene", scene_spec, "SCENE.yaml, or builtin:NAME (small_office, large_office)")
      ->required();
  app.add_option("--trajectory,-t", trajectories,
                 "Generator name (arm_sweep, adjacent_sweeps, orbit, random_walk), inline map "
                 "'{type: orbit, radius: 1.2}', generator .yaml file, or TUM file; repeat for "
                 "more sequences")
      ->required();
  app.add_option("--out,-o", out_dir, "Output folder (receives seq-01, seq-02, ...)")->required();
  app.add_option("--width", width, "Image width (default 640, or the calibration's)")
      ->check(CLI::Range(1, 8192));
  app.add_option("--height", height, "Image height (default 480, or the calibration's)")
      ->check(CLI::Range(1, 8192));
  app.add_option("--camera", camera_file, "ROS camera_info YAML (scaled to --width/--height)");
  app.add_option("--fps", fps,
                 "Frame stamps start + i / fps (default 20, like the paper's videos); 0 keeps "
                 "the trajectory's own stamps");
  app.add_option("--max-frames", max_frames, "At most this many frames per sequence (0 = all)");
  app.add_flag("--kinect", kinect, "Kinect-like sensor effects (noise, holes, range)");
  app.add_option("--sensor", sensor,
                 "Sensor model: a preset (none, kinect, realistic) or an inline map "
                 "'{preset: realistic, seed: 2}' (docs/SCENE.md); realistic adds auto-exposure, "
                 "white-balance drift and motion blur along the trajectory");
  app.add_flag("--overwrite", overwrite, "Replace existing seq-NN captures in --out");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);  // CLI11 wants them reversed
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  if (fps < 0.0 || max_frames < 0 || width < 0 || height < 0) {
    throw std::invalid_argument("--fps, --max-frames, --width and --height must not be negative");
  }

  scene::SimScene sim = scene::SimScene::FromSpec(scene_spec);
  SetSensor(kinect, sensor, &sim);
  const scene::CameraInfo camera = RenderCamera(camera_file, width, height);
  std::vector<std::vector<scene::StampedPose>> all;
  for (const std::string& spec : trajectories) {
    for (auto& t : scene::ResolveTrajectorySpec(spec, &sim)) all.push_back(std::move(t));
  }
  const auto start = std::chrono::steady_clock::now();
  const size_t total = RenderSequences(sim, camera, &all, max_frames, fps, out_dir, overwrite);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("rendered %zu frames of %dx%d in %zu sequence(s) to %s in %.1f s (%.1f frames/s)\n",
              total, camera.image_width, camera.image_height, all.size(), out_dir.c_str(),
              seconds, seconds > 0 ? total / seconds : 0.0);
  return 0;
}

}  // namespace

P2I_COMMAND("render", "Render p2i capture datasets from the synthetic scene", RunRender);

}  // namespace p2i::tools
