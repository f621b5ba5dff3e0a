/// @file lpips.h
/// @brief LPIPS-Squeeze (v0.1): the learned perceptual distance of Zhang et al. (2018) with the
/// SqueezeNet 1.1 backbone, evaluated with LibTorch (hidden behind this torch-free header).
///
/// Always label the numbers "LPIPS-Squeeze": they are NOT comparable with the LPIPS-Alex values
/// printed in NeRF papers. The weights live outside the project (../shared/models/lpips, see its
/// README); they are found through a path option or the environment variable P2I_LPIPS_WEIGHTS.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace p2i::model {

/// The message printed (and returned) when no weights file is available.
inline constexpr const char* kLpipsUnavailableMessage =
    "LPIPS-Squeeze unavailable: set P2I_LPIPS_WEIGHTS or --lpips-weights";

/// LPIPS-Squeeze distance between RGB images (0 = identical; larger = more different).
///
/// Contract: construction loads and checks the 57 tensors (SqueezeNet 1.1 features + 7 linear
/// calibration layers) and throws std::runtime_error naming the file and the missing/misshapen
/// key. After construction the object is immutable; Distance/DistanceBatch are pure functions of
/// const tensors run without autograd, so they may be called from several threads at once.
/// Computation uses LibTorch's global intra-op thread pool (this class never changes its size).
class LpipsSqueeze {
 public:
  /// Loads `weights_path` (a PyTorch zip state dict). Throws std::runtime_error when the file
  /// cannot be read or lacks a tensor / has a wrong shape.
  explicit LpipsSqueeze(const std::string& weights_path);
  ~LpipsSqueeze();
  LpipsSqueeze(const LpipsSqueeze&) = delete;
  LpipsSqueeze& operator=(const LpipsSqueeze&) = delete;

  /// `path_option` if non-empty, else $P2I_LPIPS_WEIGHTS if set and non-empty, else "". The
  /// returned path is not checked for existence. (No built-in default: tests pass
  /// ../shared/models/lpips/lpips_squeeze_v0.1.pth explicitly.)
  static std::string ResolveWeightsPath(const std::string& path_option);

  /// The metric when its weights are available, nullptr (metric missing) otherwise. Missing means
  /// no path resolved or the resolved file does not exist; `why` (optional) then receives
  /// kLpipsUnavailableMessage plus the path tried. A file that exists but is malformed throws.
  static std::unique_ptr<LpipsSqueeze> TryLoad(const std::string& path_option,
                                               std::string* why = nullptr);

  /// Distance of two RGB images (RGB channel order!) of the same size: CV_8UC3 (0..255) or
  /// CV_32FC3/CV_64FC3 in [0, 1]. Both are mapped to [-1, 1] as upstream. Images must be at least
  /// 16x16 (five stride-2 stages). Throws std::invalid_argument on a size/type mismatch.
  double Distance(const cv::Mat& a, const cv::Mat& b) const;

  /// Element-wise distances of two equally long lists (a[i] vs b[i]). Pairs of the same size are
  /// evaluated as one batch (N x 3 x H x W); mixed sizes are grouped by size.
  std::vector<double> DistanceBatch(const std::vector<cv::Mat>& a,
                                    const std::vector<cv::Mat>& b) const;

  const std::string& weights_path() const { return weights_path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string weights_path_;
};

/// The metric as "missing or value": nullopt when `metric` is null (weights unavailable).
std::optional<double> LpipsSqueezeOrMissing(const LpipsSqueeze* metric, const cv::Mat& a,
                                            const cv::Mat& b);

}  // namespace p2i::model
