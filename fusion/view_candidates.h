/// @file view_candidates.h
/// @brief What the geometry + appearance stage of the `fusion` method produces for one requested
/// view (raycast depth and normals, k candidate colours with confidences, the blend, coverage),
/// the refinement interface that turns it into the final RGB-D view, and the tensor layout a
/// refinement network takes (PackRefinementInput). Header-only, OpenCV + scene only: no Open3D,
/// no LibTorch, so model/ (the learned refinement) can include it without linking p2i_fusion.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::fusion {

/// How well the geometry and the keyframes cover one view (every served view carries it).
struct ViewCoverage {
  /// Pixels where the TSDF raycast found a surface (the TSDF observed it) / all pixels.
  double observed_fraction = 0.0;
  /// Pixels coloured by at least one visible keyframe / all pixels (<= observed_fraction; the
  /// rest of the observed pixels take the TSDF's voxel colour).
  double blended_fraction = 0.0;
  /// Mean over the blended pixels of the smallest angle (degrees) between the requested ray and
  /// the ray of a keyframe that sees the point: 0 on a training pose, grows off the trajectory.
  double mean_angle_deg = 0.0;
  /// Mean over all pixels of the per-pixel `confidence` map: one number in [0, 1] (1 = every pixel
  /// seen by a keyframe along the requested ray, 0 = nothing observed).
  double score = 0.0;
};

/// The per-view candidate structure (issue 12 points 2 and 3). All images have the size of
/// `camera`; row-major, pixel (u, v) at row v, column u.
///
/// Slots: `k` keyframes are chosen per view (nearest by model::CombinedPoseDistance to `pose`,
/// nearest first); slot j always means keyframe `keyframe_indices[j]` for every pixel of this
/// view. A slot with no keyframe (fewer than k keyframes) has zero colour and zero weight.
struct ViewCandidates {
  scene::Pose pose;          ///< the requested camera-to-world pose
  scene::CameraInfo camera;  ///< the requested output camera (any size and aspect)

  /// CV_32FC1, z-depth along the optical axis in metres from the TSDF raycast (with
  /// BlendOptions::depth "keyframes": the slots' own depths where they see the surface); 0 = no
  /// surface (the ray left the fused volume without a zero crossing: the TSDF never observed it).
  cv::Mat depth;
  /// CV_32FC3, unit surface normals in the *camera* frame of `pose` (x right, y down, z forward;
  /// facing the camera: z < 0); (0, 0, 0) where depth is 0.
  cv::Mat normals;
  /// CV_8UC1, 255 where depth > 0.
  cv::Mat observed;

  /// k x CV_32FC3, RGB in [0, 1]: the colour keyframe slot j sees at this pixel's surface point
  /// (bilinear sample at its projection); (0, 0, 0) where its weight is 0. Each map is empty
  /// when the view was rendered with CandidateRequest::slot_planes false (fusion_scene.h).
  std::vector<cv::Mat> colours;
  /// k x CV_32FC1 in [0, 1]: normalised view-dependent blend weight of slot j (unstructured
  /// lumigraph: angle + resolution penalty, zero when the point is not visible in keyframe j by a
  /// depth test against j's own depth, projects outside j, or j's depth is invalid there).
  /// Where any slot is visible the k weights sum to 1; elsewhere all are 0. Empty maps as colours'.
  std::vector<cv::Mat> weights;
  /// CV_32FC1 in [0, 1], per-pixel confidence of the blend: exp(-(a / angle_sigma)^2) with a the
  /// smallest ray angle of a visible slot, times the grazing factor; 0 where no slot is visible.
  cv::Mat confidence;
  /// CV_32FC3 RGB in [0, 1]: the TSDF's own voxel colour at the surface (the fallback where no
  /// keyframe is visible); 0 where depth is 0.
  cv::Mat tsdf_colour;
  /// CV_32FC3 RGB in [0, 1]: sum_j weights[j] * colours[j] where any slot is visible, tsdf_colour
  /// on the remaining observed pixels, 0 where depth is 0 (no hole fill here).
  cv::Mat blended;
  /// CV_8UC1, 255 where depth is 0 but `blended` holds a far-field colour (BlendOptions::
  /// far_depth_m: keyframes that saw nothing in range there); 0 elsewhere.
  cv::Mat far;

  std::vector<int> keyframe_indices;    ///< per slot: index into the scene's keyframes, -1 = none
  std::vector<std::string> keyframe_ids;
  std::vector<scene::Pose> keyframe_poses;
  ViewCoverage coverage;

  int k() const { return static_cast<int>(colours.size()); }
};

/// Channel count of PackRefinementInput for k slots.
inline int RefinementChannels(int k) { return 4 * k + 12; }

/// The tensor a refinement network takes: float32, CHW (channel-major, then rows, then columns),
/// C = RefinementChannels(k) = 4k + 12 channels of H x W = camera height x width:
///
///   [0, 3k)        candidate colours, slot j at channels 3j, 3j+1, 3j+2 (R, G, B in [0, 1])
///   [3k, 4k)       slot weights w_0 .. w_{k-1} (in [0, 1], sum 1 where blended)
///   4k, 4k+1, 4k+2 blended RGB in [0, 1]
///   4k+3           confidence in [0, 1]
///   4k+4           raycast depth * depth_scale (metres * depth_scale; 0 = no surface)
///   4k+5 .. 4k+7   normal x, y, z (camera frame, unit; 0 = no surface)
///   4k+8           observed mask (1 where depth > 0, else 0)
///   4k+9 .. 4k+11  TSDF voxel colour R, G, B in [0, 1]
///
/// The pose is not packed: a network that wants it adds it (e.g. as 7 constant channels after
/// these). `out` is resized to C * H * W. Throws std::invalid_argument on inconsistent sizes.
inline void PackRefinementInput(const ViewCandidates& c, std::vector<float>* out,
                                float depth_scale = 1.0f) {
  const int k = c.k();
  const int h = c.depth.rows, w = c.depth.cols;
  if (static_cast<int>(c.weights.size()) != k || c.depth.type() != CV_32FC1 ||
      c.normals.size() != c.depth.size() || c.blended.size() != c.depth.size() ||
      c.confidence.size() != c.depth.size() || c.tsdf_colour.size() != c.depth.size()) {
    throw std::invalid_argument("PackRefinementInput: ViewCandidates maps have inconsistent sizes");
  }
  const size_t plane = static_cast<size_t>(h) * static_cast<size_t>(w);
  out->assign(static_cast<size_t>(RefinementChannels(k)) * plane, 0.0f);
  float* o = out->data();
  auto put3 = [&](const cv::Mat& m, int ch0) {
    for (int v = 0; v < h; ++v) {
      const cv::Vec3f* row = m.ptr<cv::Vec3f>(v);
      for (int u = 0; u < w; ++u) {
        const size_t i = static_cast<size_t>(v) * w + u;
        for (int ch = 0; ch < 3; ++ch) o[(ch0 + ch) * plane + i] = row[u][ch];
      }
    }
  };
  auto put1 = [&](const cv::Mat& m, int ch0, float scale) {
    for (int v = 0; v < h; ++v) {
      const float* row = m.ptr<float>(v);
      for (int u = 0; u < w; ++u) o[ch0 * plane + static_cast<size_t>(v) * w + u] = row[u] * scale;
    }
  };
  for (int j = 0; j < k; ++j) {
    if (c.colours[j].size() != c.depth.size() || c.weights[j].size() != c.depth.size())
      throw std::invalid_argument("PackRefinementInput: slot " + std::to_string(j) +
                                  "'s colour / weight maps are missing or of the wrong size (render "
                                  "the view with CandidateRequest::slot_planes true)");
    put3(c.colours[j], 3 * j);
    put1(c.weights[j], 3 * k + j, 1.0f);
  }
  put3(c.blended, 4 * k);
  put1(c.confidence, 4 * k + 3, 1.0f);
  put1(c.depth, 4 * k + 4, depth_scale);
  put3(c.normals, 4 * k + 5);
  for (int v = 0; v < h; ++v) {
    const float* row = c.depth.ptr<float>(v);
    for (int u = 0; u < w; ++u)
      o[(4 * k + 8) * plane + static_cast<size_t>(v) * w + u] = row[u] > 0.0f ? 1.0f : 0.0f;
  }
  put3(c.tsdf_colour, 4 * k + 9);
}

/// Turns one view's candidates into the final RGB-D view (the learned refinement of issue 12
/// point 3 implements it in model/; FusionSynthesizer uses it when given one, otherwise it serves
/// the blend with hole filling). Output: rgb CV_8UC3 RGB, depth CV_32FC1 metres (0 = invalid), at
/// `candidates.camera`. Not thread-safe unless an implementation says so.
class ViewRefiner {
 public:
  virtual ~ViewRefiner() = default;
  virtual std::string Name() const = 0;
  virtual scene::RgbdSample Refine(const ViewCandidates& candidates) = 0;
  /// Parameter count and FLOPs per view (2 * MACs) at `camera`, for the bench's tables.
  virtual int64_t ParameterCount() const { return 0; }
  virtual double FlopsPerView(const scene::CameraInfo& camera) const { return 0.0; }
};

}  // namespace p2i::fusion
