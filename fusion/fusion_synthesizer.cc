/// @file fusion_synthesizer.cc
/// @brief `fusion` and `open3d_tsdf` behind model::ViewSynthesizer.
#include "fusion/fusion_synthesizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "model/push_pull_fill.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::fusion {
namespace {

void CheckCamera(const scene::CameraInfo& c, const std::string& what) {
  if (c.image_width <= 0 || c.image_height <= 0 || c.fx() <= 0.0 || c.fy() <= 0.0)
    throw std::invalid_argument(what + ": the camera needs a positive size and focal length");
}

/// Push-pull fills `v` where `known` is 0; pixels set in `far` keep their colour: it is the far
/// field's, not the fill's.
void FillKeepingFar(const cv::Mat& known, const cv::Mat& far, scene::RgbdSample* v) {
  const bool any_far = !far.empty() && cv::countNonZero(far) > 0;
  cv::Mat far_rgb;
  if (any_far) v->rgb.copyTo(far_rgb);
  model::PushPullFillRgbd(v->rgb, v->depth, known);
  if (any_far) far_rgb.copyTo(v->rgb, far);
}

}  // namespace

scene::RgbdSample ToView(const scene::Pose& pose, const cv::Mat& rgb, const cv::Mat& depth, bool fill,
                         const std::string& id, const cv::Mat& far) {
  scene::RgbdSample v;
  v.pose = pose;
  v.id = id;
  rgb.convertTo(v.rgb, CV_8UC3, 255.0);
  v.depth = depth.clone();
  if (fill) FillKeepingFar(depth > 0.0f, far, &v);
  return v;
}

FusionOptions FusionOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node, {"tsdf", "blend", "submaps", "fill_holes"}, "fusion options");
  FusionOptions o;
  if (node["tsdf"]) o.scene.tsdf = TsdfOptions::FromYaml(node["tsdf"], source);
  if (node["blend"]) o.scene.blend = BlendOptions::FromYaml(node["blend"], source);
  if (node["submaps"]) o.scene.submaps = SubmapOptions::FromYaml(node["submaps"], source);
  if (node["fill_holes"]) {
    try {
      o.fill_holes = node["fill_holes"].as<bool>();
    } catch (const YAML::Exception&) {
      r.Fail(node["fill_holes"], "fill_holes must be true or false");
    }
  }
  return o;
}

FusionSynthesizer::FusionSynthesizer(const scene::RgbdDataset& training, FusionOptions options,
                                     std::optional<scene::CameraInfo> output_camera,
                                     std::shared_ptr<ViewRefiner> refiner)
    : options_(options),
      scene_(training.camera, options.scene),
      output_camera_(output_camera ? *output_camera : training.camera),
      refiner_(std::move(refiner)) {
  CheckCamera(output_camera_, "FusionSynthesizer output");
  for (const auto& f : training.frames) scene_.AddFrame(f);
  scene_.Prepare();  // the meshes belong to training, not to the first views
  if (const std::string chosen = scene_.AutoChoices(); !chosen.empty())
    std::fprintf(stderr, "fusion: %s\n", chosen.c_str());
}

namespace {

bool SameCamera(const scene::CameraInfo& a, const scene::CameraInfo& b) {
  const auto near = [](double x, double y) { return std::fabs(x - y) <= 1e-3 * std::max(1.0, std::fabs(x)); };
  return a.image_width == b.image_width && a.image_height == b.image_height && near(a.fx(), b.fx()) &&
         near(a.fy(), b.fy()) && near(a.cx(), b.cx()) && near(a.cy(), b.cy());
}

std::string Describe(const scene::CameraInfo& c) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%dx%d, f %.2f/%.2f, c %.2f/%.2f", c.image_width, c.image_height,
                c.fx(), c.fy(), c.cx(), c.cy());
  return buf;
}

/// Copies `filler`'s view at `pose` into `v` where `hole` (CV_8UC1) is set; the filler's invalid
/// depth (0) stays 0. Returns the number of pixels coloured.
int FillFrom(model::ViewSynthesizer& filler, const scene::Pose& pose, const scene::CameraInfo& camera,
             const cv::Mat& hole, scene::RgbdSample* v) {
  const scene::CameraInfo fc = filler.Camera();
  if (!SameCamera(fc, camera)) {
    throw std::invalid_argument("fusion hole filler (" + filler.Name() + ") renders at " + Describe(fc) +
                                " but the view's camera is " + Describe(camera) +
                                ": train or export it at the view's resolution, or drop the filler");
  }
  const scene::RgbdSample g = filler.Render(pose);
  if (g.rgb.size() != hole.size() || g.rgb.type() != CV_8UC3 || g.depth.type() != CV_32FC1)
    throw std::runtime_error("fusion hole filler (" + filler.Name() + ") returned a view of another size or type");
  g.rgb.copyTo(v->rgb, hole);
  g.depth.copyTo(v->depth, hole);
  return cv::countNonZero(hole);
}

}  // namespace

scene::RgbdSample FusionSynthesizer::RenderAt(const scene::Pose& pose, const scene::CameraInfo& camera) {
  CheckCamera(camera, "FusionSynthesizer::RenderAt");
  CandidateRequest request;
  request.slot_planes = refiner_ != nullptr;  // only a refinement reads the per-slot maps
  const ViewCandidates c = scene_.RenderCandidates(pose, camera, request);
  last_coverage_ = c.coverage;
  last_filler_fraction_ = 0.0;
  scene::RgbdSample v;
  if (refiner_) {
    v = refiner_->Refine(c);
    v.pose = pose;
  } else {
    v = ToView(pose, c.blended, c.depth, options_.fill_holes && !filler_, "fusion", c.far);
  }
  if (!filler_) return v;
  const cv::Mat hole = (c.depth <= 0.0f) & (c.far == 0);  // the far field keeps its colour
  if (cv::countNonZero(hole) > 0) {
    last_filler_fraction_ = FillFrom(*filler_, pose, camera, hole, &v) /
                            (static_cast<double>(camera.image_width) * camera.image_height);
  }
  if (!refiner_ && options_.fill_holes) FillKeepingFar(v.depth > 0.0f, c.far, &v);
  return v;
}

namespace {
model::ViewGeometry GeometryOf(const ViewCoverage& c) {
  model::ViewGeometry g;
  g.observed_fraction = c.observed_fraction;
  g.keyframe_angle_deg = c.mean_angle_deg;
  return g;
}
}  // namespace

scene::RgbdSample FusionSynthesizer::Render(const scene::Pose& pose) {
  return std::move(RenderBatch({pose}).front());
}

std::vector<scene::RgbdSample> FusionSynthesizer::RenderBatch(const std::vector<scene::Pose>& poses) {
  std::vector<model::ViewGeometry> geometry;
  std::vector<scene::RgbdSample> out;
  out.reserve(poses.size());
  for (const scene::Pose& p : poses) {
    out.push_back(RenderAt(p, output_camera_));
    geometry.push_back(GeometryOf(last_coverage_));
  }
  last_geometry_ = std::move(geometry);
  return out;
}

namespace {
/// The peer is Open3D's own way to see a TSDF: its raycast, whatever the surface option says.
TsdfOptions RaycastSurface(TsdfOptions o) {
  o.surface = "raycast";
  return o;
}
}  // namespace

Open3dTsdfSynthesizer::Open3dTsdfSynthesizer(const scene::RgbdDataset& training, FusionOptions options,
                                             std::optional<scene::CameraInfo> output_camera)
    : options_(options),
      tsdf_(RaycastSurface(options.scene.tsdf.ForFrames(training.camera))),
      frame_camera_(training.camera),
      output_camera_(output_camera ? *output_camera : training.camera) {
  CheckCamera(frame_camera_, "Open3dTsdfSynthesizer training");
  CheckCamera(output_camera_, "Open3dTsdfSynthesizer output");
  for (const auto& f : training.frames) tsdf_.Integrate(f, frame_camera_);
}

scene::RgbdSample Open3dTsdfSynthesizer::Render(const scene::Pose& pose) {
  const TsdfRaycast r = tsdf_.Raycast(pose, output_camera_);
  last_hole_fraction_ =
      1.0 - static_cast<double>(cv::countNonZero(r.depth > 0.0f)) /
                (static_cast<double>(output_camera_.image_width) * output_camera_.image_height);
  return ToView(pose, r.colour, r.depth, options_.fill_holes, "open3d_tsdf");
}

}  // namespace p2i::fusion
