/// @file submaps.cc
/// @brief Local TSDF submaps and the merge of their raycasts.
#include "fusion/submaps.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include "scene/strict_yaml_reader.h"

namespace p2i::fusion {

SubmapOptions SubmapOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node, {"frames", "break_m", "break_deg", "render", "use"}, "submap options");
  SubmapOptions o = PerCaptureAuto();
  if (node["frames"]) {
    if (node["frames"].IsScalar() && node["frames"].Scalar() == "capture") {
      o.frames = SubmapOptions::kCapture;
    } else {
      o.frames = r.Int(node["frames"], "frames");
      o.use = "always";  // submaps by count, as asked (`use` below may still say auto)
    }
  }
  if (node["render"]) o.render = r.Int(node["render"], "render");
  if (node["use"]) o.use = r.String(node["use"], "use");
  r.OptionalDouble(node, "break_m", "submaps", &o.break_m);
  r.OptionalDouble(node, "break_deg", "submaps", &o.break_deg);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  return o;
}

void SubmapOptions::Validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("SubmapOptions." + what); };
  if (frames < 0) fail("frames must be >= 0 (0 = one global TSDF), got " + std::to_string(frames));
  if (!(break_m > 0.0) || !std::isfinite(break_m)) fail("break_m must be > 0");
  if (!(break_deg > 0.0) || !std::isfinite(break_deg)) fail("break_deg must be > 0");
  if (render < 1 || render > 8) fail("render must be in [1, 8], got " + std::to_string(render));
  if (use != "always" && use != "auto") fail("use must be \"always\" or \"auto\", got \"" + use + "\"");
}

std::string SubmapOptions::DescribeFrames() const {
  return per_capture() ? "capture" : std::to_string(frames);
}

SubmapSet::SubmapSet(SubmapOptions options, TsdfOptions tsdf) : options_(options), tsdf_(std::move(tsdf)) {
  options_.Validate();
  tsdf_.Validate();
}

int SubmapSet::Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera,
                         const TsdfVolume* global) {
  scene::CheckFitsCamera(frame, camera, "SubmapSet::Integrate: frame");  // before a new submap starts for it
  const auto jumps = [&] {  // last_pose_ is the previous frame's
    return scene::Pose::TranslationDistance(last_pose_, frame.pose) > options_.break_m ||
           scene::Pose::RotationDistanceDeg(last_pose_, frame.pose) > options_.break_deg;
  };
  if (Deferring()) {
    if (deferred_ == 0 || !jumps()) {  // still the first capture: the global TSDF's frames
      ++deferred_;
      last_pose_ = frame.pose;
      return -1;
    }
    if (!global)
      throw std::invalid_argument("SubmapSet::Integrate: the first capture's submap needs the global TSDF");
    maps_.push_back(Map{global->Clone(), deferred_});
    maps_.back().volume.Prepare();  // final from now on
    sealed_ = true;                 // the frame starts the next submap
  }
  bool start = maps_.empty() || sealed_ || maps_.back().frames >= options_.frames;
  if (!start) start = jumps();
  if (start) {
    if (!maps_.empty() && !sealed_) maps_.back().volume.Prepare();  // final from now on
    maps_.push_back(Map{TsdfVolume(tsdf_), 0});
    sealed_ = false;
  }
  maps_.back().volume.Integrate(frame, camera);
  ++maps_.back().frames;
  last_pose_ = frame.pose;
  return current();
}

void SubmapSet::Append(TsdfVolume volume, int frames) {
  if (frames < 0) throw std::invalid_argument("SubmapSet::Append: frames must be >= 0");
  maps_.push_back(Map{std::move(volume), frames});
  sealed_ = true;
}

void SubmapSet::Prepare() {
  for (Map& m : maps_) m.volume.Prepare();
}

int64_t FillMissingSurface(TsdfRaycast* into, const TsdfRaycast& from) {
  int64_t filled = 0;
  for (int v = 0; v < into->depth.rows; ++v) {
    float* d = into->depth.ptr<float>(v);
    const float* fd = from.depth.ptr<float>(v);
    for (int u = 0; u < into->depth.cols; ++u) {
      if (d[u] > 0.0f || !(fd[u] > 0.0f)) continue;
      d[u] = fd[u];
      into->normals.at<cv::Vec3f>(v, u) = from.normals.at<cv::Vec3f>(v, u);
      into->colour.at<cv::Vec3f>(v, u) = from.colour.at<cv::Vec3f>(v, u);
      ++filled;
    }
  }
  return filled;
}

TsdfRaycast SubmapSet::Raycast(const std::vector<int>& order, const scene::Pose& pose,
                               const scene::CameraInfo& camera, cv::Mat* from) {
  const cv::Size size(camera.image_width, camera.image_height);
  TsdfRaycast out{cv::Mat::zeros(size, CV_32FC1), cv::Mat::zeros(size, CV_32FC3),
                  cv::Mat::zeros(size, CV_32FC3)};
  if (from) *from = cv::Mat::zeros(size, CV_8UC1);
  std::vector<int> used;
  cv::Mat filled;
  for (size_t i = 0; i < order.size() && static_cast<int>(used.size()) < options_.render; ++i) {
    const int m = order[i];
    if (m < 0 || m >= static_cast<int>(maps_.size())) continue;
    if (std::find(used.begin(), used.end(), m) != used.end()) continue;
    used.push_back(m);
    const int64_t n = FillMissingFrom(maps_[static_cast<size_t>(m)].volume, pose, camera, &out,
                                      from ? &filled : nullptr);
    if (from && n > 0) from->setTo(static_cast<uint8_t>(i + 1), filled);
  }
  return out;
}

int64_t FillMissingFrom(TsdfVolume& volume, const scene::Pose& pose, const scene::CameraInfo& camera,
                        TsdfRaycast* into, cv::Mat* filled) {
  const cv::Mat missing = into->depth <= 0.0f;
  if (filled) *filled = cv::Mat::zeros(into->depth.size(), CV_8UC1);
  if (cv::countNonZero(missing) == 0) return 0;
  const cv::Rect box = cv::boundingRect(missing);
  TsdfRaycast roi{into->depth(box), into->normals(box), into->colour(box)};  // views into `into`
  const cv::Mat only = missing(box);
  const int64_t n = FillMissingSurface(
      &roi, volume.Raycast(pose, camera.Cropped(box.x, box.y, box.width, box.height), &only));
  if (filled) (*filled)(box).setTo(255, only & (roi.depth > 0.0f));
  return n;
}

TsdfStats SubmapSet::Stats() const {
  TsdfStats s;
  for (const Map& m : maps_) {
    const TsdfStats t = m.volume.Stats();
    s.frames += t.frames;
    s.blocks += t.blocks;
    s.memory_bytes += t.memory_bytes;
    s.block_volume_m3 += t.block_volume_m3;
  }
  return s;
}

}  // namespace p2i::fusion
