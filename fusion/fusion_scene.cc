/// @file fusion_scene.cc
/// @brief TSDF raycast + per-pixel visibility-tested, view-dependent keyframe blending.
#include "fusion/fusion_scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <future>
#include <stdexcept>
#include <utility>

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "fusion/fast_angle.h"
#include "fusion/keyframe_pyramid.h"
#include "fusion/keyframe_sampling.h"
#include "fusion/slot_alignment.h"
#include "model/coverage.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::fusion {
namespace {

constexpr double kRadToDeg = 57.29577951308232;

struct Slot {
  int index = -1;
  const scene::RgbdSample* frame = nullptr;
  const cv::Mat* colour = nullptr;  // the pyramid level the view reads (the frame's rgb at 0)
  const cv::Mat* depth = nullptr;   // the same level of the depth pyramid (the frame's depth at 0)
  Eigen::Matrix3f r_kw;  // world -> keyframe camera
  Eigen::Vector3f t_kw;
  Eigen::Vector3f centre;  // keyframe camera centre in the world
};

// The raycast of the view and zeroed planes for k keyframe slots.
ViewCandidates EmptyCandidates(const scene::Pose& pose, const scene::CameraInfo& camera,
                               const TsdfRaycast& ray, int k, bool slot_planes) {
  const int w = camera.image_width, h = camera.image_height;
  ViewCandidates c;
  c.pose = pose;
  c.camera = camera;
  c.depth = ray.depth;
  c.normals = ray.normals;
  c.tsdf_colour = ray.colour;
  c.observed = cv::Mat::zeros(h, w, CV_8UC1);
  c.confidence = cv::Mat::zeros(h, w, CV_32FC1);
  c.blended = cv::Mat::zeros(h, w, CV_32FC3);
  c.far = cv::Mat::zeros(h, w, CV_8UC1);
  c.colours.assign(static_cast<size_t>(k), cv::Mat());
  c.weights.assign(static_cast<size_t>(k), cv::Mat());
  if (!slot_planes) return c;
  for (int j = 0; j < k; ++j) {
    c.colours[j] = cv::Mat::zeros(h, w, CV_32FC3);
    c.weights[j] = cv::Mat::zeros(h, w, CV_32FC1);
  }
  return c;
}

// Keyframe slots for a view: nearest by pose, nearest first, minus an excluded one; each reads
// colour at pyramid `level` (0: the keyframe itself).
std::vector<Slot> SelectSlots(const std::vector<scene::RgbdSample>& keyframes,
                              const std::vector<cv::Mat>& blend_rgb,
                              const std::vector<std::vector<cv::Mat>>& colour_levels,
                              const std::vector<std::vector<cv::Mat>>& depth_levels,
                              const std::vector<scene::Pose>& poses, const scene::Pose& pose,
                              int k, int level, const CandidateRequest& request,
                              double metres_per_degree) {
  std::vector<Slot> slots;
  const size_t want = static_cast<size_t>(k) + (request.exclude_keyframe ? 1 : 0);
  for (size_t i : model::NearestPoseIndices(poses, pose, want, metres_per_degree)) {
    if (request.exclude_keyframe && static_cast<int>(i) == *request.exclude_keyframe) continue;
    if (static_cast<int>(slots.size()) == k) break;
    Slot s;
    s.index = static_cast<int>(i);
    s.frame = &keyframes[i];
    s.colour = level == 0 ? &blend_rgb[i] : &colour_levels[i][static_cast<size_t>(level - 1)];
    s.depth = level == 0 ? &keyframes[i].depth : &depth_levels[i][static_cast<size_t>(level - 1)];
    const Eigen::Matrix4d kw = keyframes[i].pose.Inverse().ToMatrix();
    s.r_kw = kw.block<3, 3>(0, 0).cast<float>();
    s.t_kw = kw.block<3, 1>(0, 3).cast<float>();
    s.centre = keyframes[i].pose.translation().cast<float>();
    slots.push_back(s);
  }
  return slots;
}

void RecordSlots(const std::vector<Slot>& slots, int k, ViewCandidates* c) {
  c->keyframe_indices.assign(static_cast<size_t>(k), -1);
  c->keyframe_ids.assign(static_cast<size_t>(k), "");
  c->keyframe_poses.assign(static_cast<size_t>(k), scene::Pose());
  for (size_t j = 0; j < slots.size(); ++j) {
    c->keyframe_indices[j] = slots[j].index;
    c->keyframe_ids[j] = slots[j].frame->id;
    c->keyframe_poses[j] = slots[j].frame->pose;
  }
}

// Sums over the pixels of a view for its CoverageSummary.
struct BlendStats {
  int64_t observed = 0, blended = 0;
  double angle_sum = 0.0, conf_sum = 0.0;
};

// The per-pixel blend of one view: which slots see the raycast point (depth test), their
// penalty (angle + resolution), grazing factor and colour, then the normalised weights, the
// blended colour and the confidence. Holds the view's constants and per-pixel scratch arrays
// (at most 16 slots, BlendOptions::Validate). Thread-compatible.
class KeyframeBlender {
 public:
  KeyframeBlender(const scene::Pose& pose, const scene::CameraInfo& camera,
                  const scene::CameraInfo& frame_camera, const BlendOptions& bo,
                  const std::vector<Slot>& slots, int level, bool slot_planes, bool keyframe_depth)
      : slots_(slots), level_(level), slot_planes_(slot_planes), keyframe_depth_(keyframe_depth) {
    bicubic_ = bo.sampling == "bicubic" ||
               (bo.sampling == "auto" &&
                UseBicubicRead(camera.fx(), camera.fy(), frame_camera.fx(), frame_camera.fy(), level));
    const Eigen::Matrix4d wc = pose.ToMatrix();
    r_wc_ = wc.block<3, 3>(0, 0).cast<float>();
    centre_ = wc.block<3, 1>(0, 3).cast<float>();
    fx_ = static_cast<float>(camera.fx()), fy_ = static_cast<float>(camera.fy());
    cx_ = static_cast<float>(camera.cx()), cy_ = static_cast<float>(camera.cy());
    kfx_ = static_cast<float>(frame_camera.fx()), kfy_ = static_cast<float>(frame_camera.fy());
    kcx_ = static_cast<float>(frame_camera.cx()), kcy_ = static_cast<float>(frame_camera.cy());
    kw_ = frame_camera.image_width, kh_ = frame_camera.image_height;
    vis_abs_ = static_cast<float>(bo.visibility_abs_m), vis_rel_ = static_cast<float>(bo.visibility_rel);
    res_w_ = static_cast<float>(bo.resolution_weight), eps_ = static_cast<float>(bo.penalty_epsilon);
    floor_g_ = static_cast<float>(bo.grazing_floor);
    sigma_ = static_cast<float>(bo.angle_sigma_deg / kRadToDeg);
    far_z_ = static_cast<float>(bo.far_depth_m);
    cubic_a_ = static_cast<float>(bo.cubic_a);
    view_z_ = r_wc_.col(2);
  }

  // Pixel (u, v) with raycast depth z and camera-frame normal n into c.
  void Pixel(int u, int v, float z, const cv::Vec3f& n, ViewCandidates* c, BlendStats* stats) {
    if (!(z > 0.0f)) {
      if (far_z_ > 0.0f) FarField(u, v, c);
      return;
    }
    ++stats->observed;
    c->observed.at<uint8_t>(v, u) = 255;
    const Eigen::Vector3f xc((u - cx_) / fx_ * z, (v - cy_) / fy_ * z, z);
    const Eigen::Vector3f xw = r_wc_ * xc + centre_;
    const float dist0 = xc.norm();
    const Eigen::Vector3f dir = (xw - centre_) / dist0;
    const Eigen::Vector3f nw = r_wc_ * Eigen::Vector3f(n[0], n[1], n[2]);
    float p_max = 0.0f;
    if (ScoreSlots(xw, dir, nw, dist0, &p_max) == 0) {
      c->blended.at<cv::Vec3f>(v, u) = c->tsdf_colour.at<cv::Vec3f>(v, u);
      return;
    }
    ++stats->blended;
    Mix(u, v, p_max, c, stats);
  }

 private:
  // A world point in a slot's keyframe: its depth there, its projection at the pyramid level read
  // (the depth and colour levels have the same size) and the keyframe's own depth at it.
  struct Projection {
    float z, lu, lv, dk;
  };
  bool Project(const Slot& s, const Eigen::Vector3f& xw, Projection* p) const {
    const Eigen::Vector3f xk = s.r_kw * xw + s.t_kw;
    if (!(xk.z() > 1e-4f)) return false;
    const float pu = kfx_ * xk.x() / xk.z() + kcx_, pv = kfy_ * xk.y() / xk.z() + kcy_;
    if (!(pu >= 0.0f && pv >= 0.0f && pu <= kw_ - 1.0f && pv <= kh_ - 1.0f)) return false;
    p->z = xk.z();
    p->lu = pu;
    p->lv = pv;
    ToPyramidLevel(level_, s.depth->cols, s.depth->rows, &p->lu, &p->lv);
    p->dk = s.depth->at<float>(static_cast<int>(p->lv + 0.5f), static_cast<int>(p->lu + 0.5f));
    return true;
  }

  // A pixel without a fused surface: the slots' colours of the point far_z_ along its ray, from
  // the slots that saw nothing nearer than 0.8 far_z_ at its projection, weighted by ray angle.
  void FarField(int u, int v, ViewCandidates* c) {
    const Eigen::Vector3f xc((u - cx_) / fx_ * far_z_, (v - cy_) / fy_ * far_z_, far_z_);
    const Eigen::Vector3f xw = r_wc_ * xc + centre_;
    const Eigen::Vector3f dir = (xw - centre_) / xc.norm();
    float p_max = 0.0f;
    int n_vis = 0;
    for (size_t j = 0; j < slots_.size(); ++j) {
      vis_[j] = false;
      const Slot& s = slots_[j];
      Projection pr;
      if (!Project(s, xw, &pr)) continue;
      if (pr.dk > 0.0f && pr.dk < 0.8f * far_z_) continue;  // it saw something nearer there
      const Eigen::Vector3f to_k = s.centre - xw;
      pen_[j] = AngleFromSinCos(dir.cross(to_k).norm(), -dir.dot(to_k));
      col_[j] = bicubic_ ? SampleBicubic(*s.colour, pr.lu, pr.lv, cubic_a_)
                         : SampleBilinear(*s.colour, pr.lu, pr.lv);
      vis_[j] = true;
      p_max = std::max(p_max, pen_[j]);
      ++n_vis;
    }
    if (n_vis == 0) return;
    float wsum = 0.0f;
    cv::Vec3f out(0.0f, 0.0f, 0.0f);
    for (size_t j = 0; j < slots_.size(); ++j) {
      if (!vis_[j]) continue;
      const float w = Weight(pen_[j], p_max);
      wsum += w;
      out += w * col_[j];
    }
    c->blended.at<cv::Vec3f>(v, u) = out / wsum;
    c->far.at<uint8_t>(v, u) = 255;
  }

  // Visibility, penalty, angle, grazing factor and colour of each slot for world point xw;
  // returns how many slots see it, *p_max the largest penalty among them.
  int ScoreSlots(const Eigen::Vector3f& xw, const Eigen::Vector3f& dir, const Eigen::Vector3f& nw,
                 float dist0, float* p_max) {
    int n_vis = 0;
    for (size_t j = 0; j < slots_.size(); ++j) {
      vis_[j] = false;
      const Slot& s = slots_[j];
      Projection pr;
      if (!Project(s, xw, &pr)) continue;
      const float lu = pr.lu, lv = pr.lv, dk = pr.dk;
      if (!(dk > 0.0f) || std::fabs(dk - pr.z) > std::max(vis_abs_, vis_rel_ * pr.z)) continue;
      const Eigen::Vector3f to_k = s.centre - xw;  // point -> keyframe camera
      const float dist_k = to_k.norm();
      // The angle between the view's ray and the keyframe's (camera -> point, i.e. -to_k);
      // AngleFromSinCos takes unnormalised sides, so to_k needs no division.
      const float a = AngleFromSinCos(dir.cross(to_k).norm(), -dir.dot(to_k));
      const float res = std::max(0.0f, (dist_k - dist0) / dist0);
      pen_[j] = a + res_w_ * res;
      ang_[j] = a;
      graze_[j] = std::max(floor_g_, nw.dot(to_k) / dist_k);
      col_[j] = bicubic_ ? SampleBicubic(*s.colour, lu, lv, cubic_a_) : SampleBilinear(*s.colour, lu, lv);
      if (keyframe_depth_) {  // the keyframe's own surface point on its ray, as the view's z
        const Eigen::Vector3f xs = s.centre + (xw - s.centre) * (dk / pr.z);
        zk_[j] = (xs - centre_).dot(view_z_);
      }
      vis_[j] = true;
      *p_max = std::max(*p_max, pen_[j]);
      ++n_vis;
    }
    return n_vis;
  }

  // The unstructured-lumigraph weight of a slot of penalty `pen` among visible slots whose
  // largest penalty is `p_max`: it falls to 0 at 1.5 p_max, so the worst of them still counts.
  float Weight(float pen, float p_max) const {
    const float q = 1.0f - pen / (1.5f * p_max + eps_);
    return q * q / (pen + eps_);
  }

  // The weights of the visible slots (Weight, times the grazing factor), the blended colour and
  // the confidence of the best-angle slot.
  void Mix(int u, int v, float p_max, ViewCandidates* c, BlendStats* stats) {
    float wsum = 0.0f, a_min = 1e9f, g_best = 0.0f;
    for (size_t j = 0; j < slots_.size(); ++j) {
      if (!vis_[j]) continue;
      wgt_[j] = Weight(pen_[j], p_max) * graze_[j];
      wsum += wgt_[j];
      if (ang_[j] < a_min) {
        a_min = ang_[j];
        g_best = graze_[j];
      }
    }
    cv::Vec3f out(0.0f, 0.0f, 0.0f);
    float z = 0.0f;
    for (size_t j = 0; j < slots_.size(); ++j) {
      if (!vis_[j]) continue;
      const float a = wgt_[j] / wsum;
      if (keyframe_depth_) z += a * zk_[j];
      if (slot_planes_) {
        c->weights[j].at<float>(v, u) = a;
        c->colours[j].at<cv::Vec3f>(v, u) = col_[j];
      }
      out += a * col_[j];
    }
    c->blended.at<cv::Vec3f>(v, u) = out;
    if (keyframe_depth_ && z > 0.0f) c->depth.at<float>(v, u) = z;
    const float conf = std::exp(-(a_min / sigma_) * (a_min / sigma_)) * g_best;
    c->confidence.at<float>(v, u) = conf;
    stats->angle_sum += a_min * kRadToDeg;
    stats->conf_sum += conf;
  }

  const std::vector<Slot>& slots_;
  int level_;  // the keyframes' colour pyramid level read (Slot::colour)
  bool slot_planes_;  // write ViewCandidates::colours / weights (CandidateRequest::slot_planes)
  bool keyframe_depth_;  // the slots' own depth (BlendOptions::depth "keyframes" or its auto choice)
  Eigen::Matrix3f r_wc_;
  Eigen::Vector3f centre_, view_z_;  // view_z_: the view's optical axis in the world
  float fx_, fy_, cx_, cy_, kfx_, kfy_, kcx_, kcy_;
  int kw_, kh_;
  float vis_abs_, vis_rel_, res_w_, eps_, floor_g_, sigma_, far_z_, cubic_a_;
  bool bicubic_ = true;
  std::array<float, 16> pen_{}, graze_{}, ang_{}, wgt_{}, zk_{};
  std::array<cv::Vec3f, 16> col_{};
  std::array<bool, 16> vis_{};
};

}  // namespace

BlendOptions BlendOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node,
              {"k", "metres_per_degree", "visibility_abs_m", "visibility_rel", "resolution_weight",
               "penalty_epsilon", "grazing_floor", "angle_sigma_deg", "keyframe_min_distance",
               "sampling", "keyframe_levels", "far_depth_m", "align_iterations",
               "align_max_shift_px", "align_flow_preset", "depth", "keyframe_denoise", "cubic_a"},
              "blend options");
  BlendOptions o;
  if (node["k"]) o.k = r.Int(node["k"], "k");
  r.OptionalDouble(node, "metres_per_degree", "blend", &o.metres_per_degree);
  r.OptionalDouble(node, "visibility_abs_m", "blend", &o.visibility_abs_m);
  r.OptionalDouble(node, "visibility_rel", "blend", &o.visibility_rel);
  r.OptionalDouble(node, "resolution_weight", "blend", &o.resolution_weight);
  r.OptionalDouble(node, "penalty_epsilon", "blend", &o.penalty_epsilon);
  r.OptionalDouble(node, "grazing_floor", "blend", &o.grazing_floor);
  r.OptionalDouble(node, "angle_sigma_deg", "blend", &o.angle_sigma_deg);
  r.OptionalDouble(node, "keyframe_min_distance", "blend", &o.keyframe_min_distance);
  r.OptionalDouble(node, "far_depth_m", "blend", &o.far_depth_m);
  r.OptionalDouble(node, "keyframe_denoise", "blend", &o.keyframe_denoise);
  r.OptionalDouble(node, "cubic_a", "blend", &o.cubic_a);
  if (node["sampling"]) o.sampling = r.String(node["sampling"], "sampling");
  if (node["depth"]) o.depth = r.String(node["depth"], "depth");
  if (node["keyframe_levels"]) o.keyframe_levels = r.Int(node["keyframe_levels"], "keyframe_levels");
  if (node["align_iterations"]) {
    const YAML::Node& a = node["align_iterations"];
    if (a.IsScalar() && a.Scalar() == "auto") {
      o.align.automatic = true;
      o.align.iterations = 1;
    } else {
      o.align.automatic = false;
      o.align.iterations = r.Int(a, "align_iterations");
    }
  }
  r.OptionalDouble(node, "align_max_shift_px", "blend", &o.align.max_shift_px);
  if (node["align_flow_preset"]) o.align.flow_preset = r.String(node["align_flow_preset"], "align_flow_preset");
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  return o;
}

void BlendOptions::Validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("BlendOptions." + what); };
  if (k < 1 || k > 16) fail("k must be in [1, 16], got " + std::to_string(k));
  if (!(metres_per_degree >= 0.0) || !std::isfinite(metres_per_degree)) fail("metres_per_degree must be >= 0");
  if (!(visibility_abs_m >= 0.0) || !std::isfinite(visibility_abs_m)) fail("visibility_abs_m must be >= 0");
  if (!(visibility_rel >= 0.0) || !std::isfinite(visibility_rel)) fail("visibility_rel must be >= 0");
  if (!(resolution_weight >= 0.0) || !std::isfinite(resolution_weight)) fail("resolution_weight must be >= 0");
  if (!(penalty_epsilon > 0.0) || !std::isfinite(penalty_epsilon)) fail("penalty_epsilon must be > 0");
  if (!(grazing_floor >= 0.0 && grazing_floor <= 1.0)) fail("grazing_floor must be in [0, 1]");
  if (!(angle_sigma_deg > 0.0) || !std::isfinite(angle_sigma_deg)) fail("angle_sigma_deg must be > 0");
  if (!(keyframe_min_distance >= 0.0) || !std::isfinite(keyframe_min_distance))
    fail("keyframe_min_distance must be >= 0");
  if (!(far_depth_m >= 0.0) || !std::isfinite(far_depth_m))
    fail("far_depth_m must be >= 0 (0 = off), got " + std::to_string(far_depth_m));
  if (!(keyframe_denoise >= 0.0 && keyframe_denoise <= 64.0))
    fail("keyframe_denoise must be in [0, 64] grey levels (0 = off), got " + std::to_string(keyframe_denoise));
  if (!(cubic_a >= -1.0 && cubic_a <= 0.0))
    fail("cubic_a must be in [-1, 0] (-0.5 Catmull-Rom, -0.75 OpenCV's INTER_CUBIC), got " +
         std::to_string(cubic_a));
  if (keyframe_levels < 0 || keyframe_levels > 6)
    fail("keyframe_levels must be in [0, 6], got " + std::to_string(keyframe_levels));
  if (sampling != "auto" && sampling != "bicubic" && sampling != "bilinear")
    fail("sampling must be auto, bicubic or bilinear, got '" + sampling + "'");
  if (depth != "raycast" && depth != "keyframes" && depth != "auto")
    fail("depth must be raycast, keyframes or auto, got '" + depth + "'");
  if (align.iterations < 0 || align.iterations > 4)
    fail("align_iterations must be auto or in [0, 4] (0 = off), got " + std::to_string(align.iterations));
  if (align.automatic && align.iterations < 1)
    fail("align_iterations auto needs at least one round to choose, got " + std::to_string(align.iterations));
  if (!(align.max_shift_px > 0.0 && align.max_shift_px <= 16.0))
    fail("align_max_shift_px must be in (0, 16], got " + std::to_string(align.max_shift_px));
  try {
    DisPreset(align.flow_preset);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

FusionSceneOptions FusionSceneOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node, {"tsdf", "blend", "submaps"}, "fusion scene options");
  FusionSceneOptions o;
  if (node["tsdf"]) o.tsdf = TsdfOptions::FromYaml(node["tsdf"], source);
  if (node["blend"]) o.blend = BlendOptions::FromYaml(node["blend"], source);
  if (node["submaps"]) o.submaps = SubmapOptions::FromYaml(node["submaps"], source);
  return o;
}

void FusionSceneOptions::Validate() const {
  tsdf.Validate();
  blend.Validate();
  submaps.Validate();
}

namespace {

/// `options`, validated, with the TSDF's auto block size resolved for the frames' camera (the
/// global TSDF and the submaps share it).
FusionSceneOptions Resolved(FusionSceneOptions options, const scene::CameraInfo& frames) {
  options.Validate();
  options.tsdf = options.tsdf.ForFrames(frames);
  return options;
}

}  // namespace

FusionScene::FusionScene(scene::CameraInfo frame_camera, FusionSceneOptions options)
    : frame_camera_(std::move(frame_camera)),
      options_(Resolved(options, frame_camera_)),
      tsdf_(options_.tsdf),
      blocks_auto_(options.tsdf.block_resolution == 0) {
  if (frame_camera_.image_width <= 0 || frame_camera_.image_height <= 0 ||
      frame_camera_.fx() <= 0.0 || frame_camera_.fy() <= 0.0) {
    throw std::invalid_argument("FusionScene: the frame camera needs a positive size and focal length");
  }
  if (options_.submaps.enabled()) submaps_.emplace(options_.submaps, options_.tsdf);
}

void FusionScene::Integrate(const scene::RgbdSample& frame) {
  if (!submaps_) {
    tsdf_.Integrate(frame, frame_camera_);
    return;
  }
  if (submaps_->Deferring()) {
    // One capture so far: its frames are the global TSDF's alone. At a pose jump the submaps copy
    // the global TSDF as it is (the first capture's submap) before this frame enters it.
    scene::CheckFitsCamera(frame, frame_camera_, "FusionScene::Integrate: frame");
    submaps_->Integrate(frame, frame_camera_, &tsdf_);
    if (submaps_->size() > 0)
      std::replace(keyframe_submap_.begin(), keyframe_submap_.end(), -1, 0);  // the first capture's
    tsdf_.Integrate(frame, frame_camera_);
    return;
  }
  // The global TSDF and the current submap are independent volumes: the submap integrates on a
  // second thread while this one integrates the global TSDF (same result as one after the other;
  // a 640x480 frame then costs one integration's time, not two). The future's destructor waits
  // for the submap when the global TSDF throws; get() rethrows the submap's error.
  auto submap = std::async(std::launch::async, [&] { submaps_->Integrate(frame, frame_camera_); });
  tsdf_.Integrate(frame, frame_camera_);
  submap.get();
}

void FusionScene::Prepare() {
  tsdf_.Prepare();
  if (submaps_) submaps_->Prepare();
  if (submaps_ && options_.submaps.use == "auto") submap_choice_ = ChooseSubmaps(*this);
  if (options_.blend.depth == "auto") depth_choice_ = ChooseDepthSource(*this);
  if (options_.blend.align.automatic) align_choice_ = ChooseAlignment(*this);
}

std::string FusionScene::AutoChoices() const {
  std::string out = blocks_auto_ ? options_.tsdf.DescribeBlockChoice(frame_camera_) : "";
  if (submaps_ && options_.submaps.use == "auto" && submap_choice_.frames > 0)
    out += (out.empty() ? "" : "; ") + submap_choice_.Describe();
  if (options_.blend.depth == "auto" && depth_choice_.frames > 0)
    out += (out.empty() ? "" : "; ") + depth_choice_.Describe();
  if (options_.blend.align.automatic && align_choice_.frames > 0)
    out += (out.empty() ? "" : "; ") + align_choice_.Describe();
  return out;
}

void FusionScene::RestoreSubmaps(SubmapSet submaps, std::vector<int> keyframe_submaps) {
  if (keyframe_submaps.size() != keyframes_.size()) {
    throw std::invalid_argument("FusionScene::RestoreSubmaps: " + std::to_string(keyframe_submaps.size()) +
                                " keyframe submaps for " + std::to_string(keyframes_.size()) + " keyframes");
  }
  for (int m : keyframe_submaps) {
    if (m < -1 || m >= static_cast<int>(submaps.size()))
      throw std::invalid_argument("FusionScene::RestoreSubmaps: keyframe submap " + std::to_string(m) +
                                  " outside [-1, " + std::to_string(submaps.size()) + ")");
  }
  options_.submaps = submaps.options();
  submaps_.emplace(std::move(submaps));
  keyframe_submap_ = std::move(keyframe_submaps);
}

bool FusionScene::AddFrame(const scene::RgbdSample& frame, bool integrate) {
  scene::CheckFitsCamera(frame, frame_camera_, "FusionScene::AddFrame: frame");
  if (integrate) Integrate(frame);
  const double min_d = options_.blend.keyframe_min_distance;
  if (min_d > 0.0 && !poses_.empty()) {
    const auto nearest = model::NearestPoseIndices(poses_, frame.pose, 1, options_.blend.metres_per_degree);
    if (model::CombinedPoseDistance(poses_[nearest.front()], frame.pose,
                                    options_.blend.metres_per_degree) < min_d)
      return false;
  }
  scene::RgbdSample kf;
  kf.stamp = frame.stamp;
  kf.pose = frame.pose;
  kf.id = frame.id;
  kf.rgb = frame.rgb.clone();
  kf.depth = frame.depth.clone();
  cv::Mat read;  // a new buffer when smoothed (the filter cannot work in place), else kf.rgb's
  if (options_.blend.keyframe_denoise > 0.0)
    cv::bilateralFilter(kf.rgb, read, 5, options_.blend.keyframe_denoise, 1.0, cv::BORDER_REPLICATE);
  else
    read = kf.rgb;
  blend_rgb_.push_back(read);
  colour_levels_.push_back(ColourPyramid(read, options_.blend.keyframe_levels));
  depth_levels_.push_back(DepthPyramid(kf.depth, options_.blend.keyframe_levels));
  keyframes_.push_back(std::move(kf));
  poses_.push_back(frame.pose);
  keyframe_submap_.push_back(submaps_ ? submaps_->current() : -1);
  return true;
}

TsdfRaycast FusionScene::Surface(const std::vector<int>& slot_keyframes, const scene::Pose& pose,
                                 const scene::CameraInfo& camera, bool use_submaps) {
  if (!use_submaps || !submaps_ || submaps_->size() == 0) return tsdf_.Raycast(pose, camera);
  std::vector<int> order;
  for (int i : slot_keyframes) order.push_back(keyframe_submap_.at(static_cast<size_t>(i)));
  TsdfRaycast ray = submaps_->Raycast(order, pose, camera);
  FillMissingFrom(tsdf_, pose, camera, &ray);
  return ray;
}

ViewCandidates FusionScene::RenderCandidates(const scene::Pose& pose, const scene::CameraInfo& camera,
                                             const CandidateRequest& request) {
  const int k = options_.blend.k;
  const int built = colour_levels_.empty() ? 0 : static_cast<int>(colour_levels_.front().size());
  const int level = PyramidLevelFor(camera.fx(), camera.fy(), frame_camera_.fx(), frame_camera_.fy(),
                                    std::min(built, options_.blend.keyframe_levels));
  const std::vector<Slot> slots = SelectSlots(keyframes_, blend_rgb_, colour_levels_, depth_levels_, poses_, pose, k,
                                              level, request, options_.blend.metres_per_degree);
  std::vector<int> slot_keyframes;
  for (const Slot& s : slots) slot_keyframes.push_back(s.index);
  const bool align = request.align.value_or(aligned());  // aligning reads the slot planes
  const bool planes = request.slot_planes || align;
  ViewCandidates c = EmptyCandidates(pose, camera, Surface(slot_keyframes, pose, camera, request.submaps.value_or(uses_submaps())), k, planes);
  RecordSlots(slots, k, &c);
  KeyframeBlender blender(pose, camera, frame_camera_, options_.blend, slots, level, planes,
                          request.keyframe_depth.value_or(keyframe_depth()));
  BlendStats stats;
  for (int v = 0; v < camera.image_height; ++v) {
    const float* drow = c.depth.ptr<float>(v);
    const cv::Vec3f* nrow = c.normals.ptr<cv::Vec3f>(v);
    for (int u = 0; u < camera.image_width; ++u) blender.Pixel(u, v, drow[u], nrow[u], &c, &stats);
  }
  const double n = static_cast<double>(camera.image_width) * camera.image_height;
  c.coverage.observed_fraction = stats.observed / n;
  c.coverage.blended_fraction = stats.blended / n;
  c.coverage.mean_angle_deg =
      stats.blended > 0 ? stats.angle_sum / static_cast<double>(stats.blended) : 0.0;
  c.coverage.score = stats.conf_sum / n;
  if (align) {
    SlotAlignmentOptions rounds = options_.blend.align;
    rounds.iterations = std::max(1, rounds.iterations);  // a request may ask for it when it is off
    AlignSlots(rounds, &c);
  }
  if (!request.slot_planes) {
    for (cv::Mat& m : c.colours) m.release();
    for (cv::Mat& m : c.weights) m.release();
  }
  return c;
}

}  // namespace p2i::fusion
