/// @file sim_ceiling.h
/// @brief Ceiling rows of `p2i bench` on a sim scene (config key `ceiling`): the scene's own
/// render at each test pose, scored against the test frames as a method is. The test frames
/// carry what the sensor model adds (RGB noise, exposure and white-balance drift over time,
/// motion blur along the sweep); a view made from a pose alone cannot reproduce most of it. How
/// far even the scene's exact render stays from those frames is the ceiling of every method in
/// the run, and says how much of a target (e.g. SSIM warp + 0.03) is left to reach at all.
/// Not a method: it reads the sim, which no user has.
#pragma once

#include <string>
#include <unordered_map>

#include "model/view_synthesizer.h"
#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_scene.h"
#include "scene/sim_sensor_options.h"

namespace p2i::eval {

/// "exact, auto_exposure, colour": the ceiling kinds, for messages.
std::string CeilingKinds();
bool IsCeilingKind(const std::string& kind);

/// The sensor options a ceiling `kind` renders with, from the data's `sensor`:
/// - "exact": pixel area (pixel_samples) kept, everything else off: the scene as it is;
/// - "auto_exposure": also the auto-exposure, a function of what the view shows (so a view made
///   from a pose could reproduce it), without the drifts, which are functions of time;
/// - "colour": also the frame's exposure and white balance (auto-exposure and the drifts at the
///   test frame's stamp): what remains against it is RGB noise, motion blur and depth noise.
/// Throws std::invalid_argument naming the kinds otherwise.
scene::SimSensorOptions CeilingSensor(const scene::SimSensorOptions& sensor, const std::string& kind);

/// One ceiling row's views: the sim rendered at the requested pose through the data's render
/// camera with CeilingSensor(kind), centre-cropped and resized to width x height as the bench's
/// ground truth is (scene::CenterCropResizeSample). A pose of `test` renders at that frame's
/// stamp (the drifts are functions of time); any other pose at stamp 0.
class SimCeilingView : public model::ViewSynthesizer {
 public:
  SimCeilingView(const scene::SimScene& sim, const std::string& kind, scene::CameraInfo render_camera,
                 int width, int height, const scene::RgbdDataset& test);
  std::string Name() const override { return "ceiling_" + kind_; }
  scene::CameraInfo Camera() const override;
  scene::RgbdSample Render(const scene::Pose& pose) override;

 private:
  scene::SimScene sim_;
  std::string kind_;
  scene::CameraInfo render_camera_;
  int width_, height_;
  std::unordered_map<std::string, double> stamps_;  ///< test pose (7 values as text) -> stamp
};

}  // namespace p2i::eval
