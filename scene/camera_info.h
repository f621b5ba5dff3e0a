/// @file camera_info.h
/// @brief Pinhole camera calibration with the fields of ROS sensor_msgs/CameraInfo.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace p2i::scene {

/// Calibration of one camera, as in a ROS camera_info YAML file. Intrinsics are in pixels for
/// an image of image_width x image_height. A value type: thread-compatible.
struct CameraInfo {
  std::string camera_name = "camera";
  int image_width = 0;
  int image_height = 0;
  std::string distortion_model = "plumb_bob";
  std::vector<double> distortion_coefficients;           ///< D (5 for plumb_bob)
  std::array<double, 9> camera_matrix{};                 ///< K, row-major
  std::array<double, 9> rectification_matrix{1, 0, 0, 0, 1, 0, 0, 0, 1};  ///< R
  std::array<double, 12> projection_matrix{};            ///< P, row-major 3x4

  double fx() const { return camera_matrix[0]; }
  double fy() const { return camera_matrix[4]; }
  double cx() const { return camera_matrix[2]; }
  double cy() const { return camera_matrix[5]; }
  Eigen::Matrix3d K() const;

  /// An undistorted pinhole camera; P = [K | 0], R = I, D = zeros(5).
  static CameraInfo Pinhole(int width, int height, double fx, double fy, double cx, double cy,
                            const std::string& name = "camera");

  /// Reads a ROS camera_info YAML file. Throws std::runtime_error naming the file and key on a
  /// missing or unknown key, a wrong matrix size, or values that fail Validate().
  static CameraInfo FromYamlFile(const std::string& path);
  /// Same, from YAML text; `source` names it in error messages.
  static CameraInfo FromYamlString(const std::string& text, const std::string& source = "<string>");
  std::string ToYamlString() const;
  /// Writes atomically (temporary file + rename).
  void ToYamlFile(const std::string& path) const;

  /// Throws std::invalid_argument saying what is wrong: non-positive size or focal length,
  /// principal point outside the image, non-finite values, wrong distortion count.
  void Validate() const;

  /// The calibration for the image resized to new_width x new_height (K and P scaled per axis).
  CameraInfo Scaled(int new_width, int new_height) const;
  /// The calibration for the crop of width x height starting at pixel (x0, y0).
  CameraInfo Cropped(int x0, int y0, int width, int height) const;
  // Centre crop + resize to a training resolution: scene::CenterCropResizeCamera (image_ops.h),
  // beside the pixel operation it matches.

  bool equals(const CameraInfo& other, double tol = 1e-9) const;
};

}  // namespace p2i::scene
