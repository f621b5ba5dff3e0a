/// @file sim_ceiling.cc
/// @brief The sim's own render as a ceiling row (see sim_ceiling.h).
#include "eval/sim_ceiling.h"

#include <cstdio>
#include <stdexcept>
#include <utility>

#include "scene/image_ops.h"

namespace p2i::eval {
namespace {

std::string PoseKey(const scene::Pose& pose) {
  const auto v = pose.ToVector7();
  std::string key;
  char buf[32];
  for (int i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof(buf), "%.17g,", v[i]);
    key += buf;
  }
  return key;
}

}  // namespace

std::string CeilingKinds() { return "exact, auto_exposure, colour"; }

bool IsCeilingKind(const std::string& kind) {
  return kind == "exact" || kind == "auto_exposure" || kind == "colour";
}

scene::SimSensorOptions CeilingSensor(const scene::SimSensorOptions& sensor, const std::string& kind) {
  if (!IsCeilingKind(kind))
    throw std::invalid_argument("ceiling kind '" + kind + "' is not one of " + CeilingKinds());
  scene::SimSensorOptions o;  // everything off
  o.pixel_samples = sensor.pixel_samples;
  o.seed = sensor.seed;
  if (kind == "auto_exposure" || kind == "colour") {
    o.auto_exposure = sensor.auto_exposure;
    o.exposure_target = sensor.exposure_target;
  }
  if (kind == "colour") {
    o.exposure_drift = sensor.exposure_drift;
    o.white_balance_drift = sensor.white_balance_drift;
    o.drift_period_s = sensor.drift_period_s;
  }
  o.Validate();
  return o;
}

SimCeilingView::SimCeilingView(const scene::SimScene& sim, const std::string& kind,
                               scene::CameraInfo render_camera, int width, int height,
                               const scene::RgbdDataset& test)
    : sim_(sim), kind_(kind), render_camera_(std::move(render_camera)), width_(width), height_(height) {
  sim_.set_sensor_options(CeilingSensor(sim.sensor_options(), kind));
  for (const auto& f : test.frames) stamps_[PoseKey(f.pose)] = f.stamp;
}

scene::CameraInfo SimCeilingView::Camera() const {
  return scene::CenterCropResizeCamera(render_camera_, width_, height_);
}

scene::RgbdSample SimCeilingView::Render(const scene::Pose& pose) {
  const auto it = stamps_.find(PoseKey(pose));
  const double stamp = it == stamps_.end() ? 0.0 : it->second;
  scene::RgbdSample s = scene::CenterCropResizeSample(sim_.Render(pose, render_camera_, stamp), width_, height_);
  s.pose = pose;
  return s;
}

}  // namespace p2i::eval
