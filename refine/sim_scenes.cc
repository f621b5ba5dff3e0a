/// @file sim_scenes.cc
/// @brief Randomised sim scenes for the cross-scene refinement (see refine_sim_scenes.h).
#include "refine/sim_scenes.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace p2i::refine {

void SimScenesOptions::Validate() const {
  if (scenes < 1) throw std::invalid_argument("SimScenesOptions: scenes must be >= 1");
  if (bases.empty()) throw std::invalid_argument("SimScenesOptions: bases is empty");
  if (frames < 2) throw std::invalid_argument("SimScenesOptions: frames must be >= 2");
  if (frame_step < 1) throw std::invalid_argument("SimScenesOptions: frame_step must be >= 1");
  if (width < 8 || height < 8)
    throw std::invalid_argument("SimScenesOptions: width and height must be >= 8");
  if (sensor != "kinect" && sensor != "realistic")
    throw std::invalid_argument("SimScenesOptions: sensor '" + sensor +
                                "' is not a sensor model (use kinect or realistic)");
  if (!(pose_noise_m >= 0.0 && pose_noise_m <= 0.5) || !(pose_noise_deg >= 0.0 && pose_noise_deg <= 30.0))
    throw std::invalid_argument("SimScenesOptions: pose_noise_m must be in [0, 0.5] and "
                                "pose_noise_deg in [0, 30]");
  scene::SimSensorOptions render;  // the sensor's own rule for the rays per pixel
  render.pixel_samples = pixel_samples;
  try {
    render.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("SimScenesOptions: ") + e.what());
  }
}

scene::Pose PerturbPose(const scene::Pose& pose, double sigma_m, double sigma_deg,
                        std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d dt(sigma_m * n(rng), sigma_m * n(rng), sigma_m * n(rng));
  Eigen::Vector3d axis(n(rng), n(rng), n(rng));
  if (axis.norm() < 1e-9) axis = Eigen::Vector3d::UnitZ();
  const double angle = sigma_deg * n(rng) * M_PI / 180.0;
  const Eigen::Quaterniond dq(Eigen::AngleAxisd(angle, axis.normalized()));
  return scene::Pose(pose.translation() + dt, pose.rotation() * dq);
}

scene::SimScene MakeSimVariant(const std::string& base, int index, uint64_t seed,
                               const std::string& sensor, int pixel_samples) {
  scene::SimSceneDescription d = scene::SimScene::BuiltIn(base).description();
  std::mt19937_64 rng(seed * 1000003ULL + static_cast<uint64_t>(index) * 7919ULL + 17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const scene::SimTexture kinds[] = {scene::SimTexture::kChecker, scene::SimTexture::kTiles,
                                     scene::SimTexture::kWood,    scene::SimTexture::kNoise,
                                     scene::SimTexture::kPoster,  scene::SimTexture::kStripes,
                                     scene::SimTexture::kSolid};
  for (auto& m : d.materials) {
    if (u(rng) < 0.6) m.texture = kinds[static_cast<int>(u(rng) * 7) % 7];
    for (int c = 0; c < 3; ++c) {
      m.color[c] = std::clamp(m.color[c] * (0.6 + 0.8 * u(rng)) + 0.2 * (u(rng) - 0.5), 0.02, 0.98);
      m.color2[c] = std::clamp(m.color2[c] * (0.6 + 0.8 * u(rng)) + 0.2 * (u(rng) - 0.5), 0.02, 0.98);
    }
    m.scale = std::max(0.02, m.scale * (0.5 + u(rng)));
    m.seed = static_cast<uint32_t>(rng());
  }
  d.ambient = 0.15 + 0.3 * u(rng);
  for (auto& l : d.lights) {
    l.intensity *= 0.5 + u(rng);
    const double tint = 0.15 * (u(rng) - 0.5);
    l.color = Eigen::Vector3d(1.0 + tint, 1.0, 1.0 - tint);
    if (l.type == scene::SimLight::Type::kPoint) {
      l.position.x() += 0.8 * (u(rng) - 0.5);
      l.position.y() += 0.8 * (u(rng) - 0.5);
    }
  }
  d.name = base + "_v" + std::to_string(index);
  d.Validate();
  scene::SimSensorOptions s;
  if (index % 3 != 0) {  // every third variant keeps the exact render
    const auto sensor_seed = static_cast<uint32_t>(rng());
    s = scene::SimSensorOptions::FromPreset(sensor, sensor_seed);
    s.rgb_noise_sigma = 3.0 * u(rng);
    s.depth_dropout = 0.05 * u(rng);
  }
  s.pixel_samples = pixel_samples;
  return scene::SimScene(d, s);
}

std::vector<SimTrainingScene> MakeSimScenes(const SimScenesOptions& options) {
  options.Validate();
  std::vector<SimTrainingScene> out;
  const scene::CameraInfo camera = scene::SimScene::DefaultCamera(options.width, options.height);
  for (int i = 0; i < options.scenes; ++i) {
    const std::string& base = options.bases[static_cast<size_t>(i) % options.bases.size()];
    const scene::SimScene sim = MakeSimVariant(base, i, options.seed, options.sensor, options.pixel_samples);
    scene::RandomWalkOptions walk;
    walk.seed = static_cast<uint32_t>(options.seed * 31 + static_cast<uint64_t>(i));
    walk.duration = (options.frames * options.frame_step + 1) / walk.rate_hz;
    const std::vector<scene::StampedPose> poses = scene::GenerateRandomWalk(walk, sim);
    SimTrainingScene s;
    s.name = sim.description().name;
    s.frames.camera = camera;
    // Its own stream, so the renders (and the scenes of pose_noise 0) do not change with it.
    std::mt19937_64 pose_rng(options.seed * 7777ULL + static_cast<uint64_t>(i) * 104729ULL + 3);
    const double noise_scale = std::uniform_real_distribution<double>(0.0, 1.0)(pose_rng);
    const bool noisy = options.pose_noise_m > 0.0 || options.pose_noise_deg > 0.0;
    for (size_t k = 0; k < poses.size() && s.frames.frames.size() < static_cast<size_t>(options.frames);
         k += static_cast<size_t>(options.frame_step)) {
      scene::RgbdSample f = sim.RenderOnTrajectory(poses, k, camera);  // blur when the sensor has it
      if (noisy)
        f.pose = PerturbPose(f.pose, noise_scale * options.pose_noise_m,
                             noise_scale * options.pose_noise_deg, pose_rng);
      f.id = s.name + "/" + std::to_string(k);
      s.frames.frames.push_back(std::move(f));
    }
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace p2i::refine
