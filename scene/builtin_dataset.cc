/// @file builtin_dataset.cc
/// @brief `builtin:NAME` training data: a built-in sim scene along the default arm sweep.
#include "scene/builtin_dataset.h"

#include <stdexcept>
#include <vector>

#include "scene/image_ops.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::scene {

const char kBuiltinPrefix[] = "builtin:";

bool IsBuiltinSpec(const std::string& spec) { return spec.rfind(kBuiltinPrefix, 0) == 0; }

void BuiltinDatasetOptions::Validate() const {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("built-in training data: width and height must be > 0, got " +
                                std::to_string(width) + "x" + std::to_string(height));
  }
  if (stride < 1) {
    throw std::invalid_argument("built-in training data: stride must be >= 1, got " +
                                std::to_string(stride));
  }
  if (max_frames < 0) {
    throw std::invalid_argument("built-in training data: max_frames must be >= 0, got " +
                                std::to_string(max_frames));
  }
}

RgbdDataset RenderBuiltinDataset(const std::string& spec, const BuiltinDatasetOptions& options) {
  if (!IsBuiltinSpec(spec)) {
    throw std::invalid_argument("'" + spec + "' is not a built-in scene (builtin:NAME)");
  }
  try {
    options.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("'" + spec + "': " + e.what());
  }
  const SimScene sim = SimScene::FromSpec(spec);
  const std::vector<StampedPose> sweep = GenerateArmSweep({});
  std::vector<size_t> picked;
  for (size_t i = 0; i < sweep.size(); i += options.stride) picked.push_back(i);
  if (options.max_frames > 0 && picked.size() > static_cast<size_t>(options.max_frames)) {
    std::vector<size_t> even;
    const size_t n = static_cast<size_t>(options.max_frames);
    for (size_t k = 0; k < n; ++k) even.push_back(picked[n == 1 ? 0 : k * (picked.size() - 1) / (n - 1)]);
    picked = even;
  }
  RgbdDataset out;
  // The frames the sim camera (4:3, f = 525 at 640 px) delivers, centre-cropped and resized to
  // width x height, as the trainer and the monitor see them: a square view has the crop's field
  // of view, not the full width's (DefaultCamera(64, 64) has f = 52.5; the crop f = 70).
  out.camera = CenterCropResizeCamera(SimScene::DefaultCamera(640, 480), options.width, options.height);
  for (size_t i : picked) {
    RgbdSample s;
    if (options.with_frames) s = sim.Render(sweep[i].pose, out.camera, sweep[i].stamp);
    s.stamp = sweep[i].stamp;
    s.pose = sweep[i].pose;
    s.id = "sweep/" + std::to_string(i);
    out.frames.push_back(std::move(s));
  }
  return out;
}

}  // namespace p2i::scene
