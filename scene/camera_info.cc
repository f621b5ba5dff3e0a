/// @file camera_info.cc
/// @brief ROS camera_info YAML IO, validation and the intrinsics of resized / cropped images.
#include "scene/camera_info.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace p2i::scene {
namespace {

// Number of distortion coefficients each supported model expects (as in ROS image_geometry).
const std::map<std::string, int>& DistortionCounts() {
  static const std::map<std::string, int> kCounts = {
      {"plumb_bob", 5}, {"rational_polynomial", 8}, {"equidistant", 4}};
  return kCounts;
}

int LineOf(const YAML::Node& node) {
  return node.Mark().is_null() ? 0 : node.Mark().line + 1;
}

[[noreturn]] void Fail(const std::string& source, const YAML::Node& node, const std::string& what) {
  throw std::runtime_error(source + ":" + std::to_string(LineOf(node)) + ": camera_info: " + what);
}

// The shortest decimal text that reads back as exactly the same double, so files stay readable
// ("525", "0.2624") and a write/read round trip is lossless.
std::string FormatDouble(double v) {
  char buf[64];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string FormatList(const double* data, size_t n) {
  std::string out = "[";
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) out += ", ";
    out += FormatDouble(data[i]);
  }
  return out + "]";
}

void WriteMatrix(std::ostringstream& out, const char* key, int rows, int cols,
                 const double* data) {
  out << key << ":\n  rows: " << rows << "\n  cols: " << cols
      << "\n  data: " << FormatList(data, static_cast<size_t>(rows) * cols) << "\n";
}

template <typename T>
T Scalar(const YAML::Node& node, const std::string& key, const std::string& source) {
  if (!node.IsScalar()) Fail(source, node, "'" + key + "' must be a scalar");
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    Fail(source, node, "'" + key + "' has an invalid value '" + node.Scalar() + "'");
  }
}

// Reads {rows, cols, data}. expected_rows / expected_cols < 0 means "any"; the data length must
// equal rows * cols.
std::vector<double> ReadMatrix(const YAML::Node& node, const std::string& key, int expected_rows,
                               int expected_cols, const std::string& source) {
  if (!node.IsMap()) Fail(source, node, "'" + key + "' must be a map {rows, cols, data}");
  static const std::set<std::string> kKeys = {"rows", "cols", "data"};
  for (const auto& kv : node) {
    const std::string sub = kv.first.as<std::string>();
    if (kKeys.count(sub) == 0) {
      Fail(source, kv.first,
           "unknown key '" + key + "." + sub + "' (expected rows, cols, data)");
    }
  }
  for (const char* sub : {"rows", "cols", "data"}) {
    if (!node[sub]) Fail(source, node, "'" + key + "' is missing '" + sub + "'");
  }
  const int rows = Scalar<int>(node["rows"], key + ".rows", source);
  const int cols = Scalar<int>(node["cols"], key + ".cols", source);
  if ((expected_rows >= 0 && rows != expected_rows) ||
      (expected_cols >= 0 && cols != expected_cols)) {
    Fail(source, node,
         "'" + key + "' is " + std::to_string(rows) + "x" + std::to_string(cols) +
             ", expected " + (expected_rows >= 0 ? std::to_string(expected_rows) : "N") + "x" +
             (expected_cols >= 0 ? std::to_string(expected_cols) : "N"));
  }
  const YAML::Node data = node["data"];
  if (!data.IsSequence()) Fail(source, data, "'" + key + ".data' must be a list of numbers");
  if (rows < 0 || cols < 0 || data.size() != static_cast<size_t>(rows) * cols) {
    Fail(source, data,
         "'" + key + ".data' has " + std::to_string(data.size()) + " values, rows x cols = " +
             std::to_string(rows) + "x" + std::to_string(cols));
  }
  std::vector<double> values;
  values.reserve(data.size());
  for (const auto& v : data) values.push_back(Scalar<double>(v, key + ".data", source));
  return values;
}

template <size_t N>
bool AllFinite(const std::array<double, N>& a) {
  for (double v : a) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

template <size_t N>
bool Near(const std::array<double, N>& a, const std::array<double, N>& b, double tol) {
  for (size_t i = 0; i < N; ++i) {
    if (!(std::abs(a[i] - b[i]) <= tol)) return false;
  }
  return true;
}

// Resizing by s maps continuous pixel coordinate u (pixel centres at integers, as OpenCV's
// cv::resize does) to (u + 0.5) * s - 0.5. Focal lengths scale by s.
void ScaleRow(double* row, double s, int cols) {
  // row = [f, skew, c, (t)] for the x row or [0, f, c, (t)] for the y row.
  const double c = row[2];
  for (int i = 0; i < cols; ++i) row[i] *= s;
  row[2] = (c + 0.5) * s - 0.5;
}

}  // namespace

Eigen::Matrix3d CameraInfo::K() const {
  Eigen::Matrix3d k;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) k(r, c) = camera_matrix[r * 3 + c];
  }
  return k;
}

CameraInfo CameraInfo::Pinhole(int width, int height, double fx, double fy, double cx, double cy,
                               const std::string& name) {
  CameraInfo info;
  info.camera_name = name;
  info.image_width = width;
  info.image_height = height;
  info.distortion_model = "plumb_bob";
  info.distortion_coefficients.assign(5, 0.0);
  info.camera_matrix = {fx, 0, cx, 0, fy, cy, 0, 0, 1};
  info.rectification_matrix = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.projection_matrix = {fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0};
  return info;
}

CameraInfo CameraInfo::FromYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("camera_info: cannot open '" + path +
                             "' (check the path; calibration files live in calib/)");
  }
  std::stringstream text;
  text << in.rdbuf();
  return FromYamlString(text.str(), path);
}

CameraInfo CameraInfo::FromYamlString(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source + ":" + std::to_string(e.mark.line + 1) +
                             ": camera_info: YAML syntax error: " + e.msg);
  }
  if (!root.IsMap()) Fail(source, root, "the file must be a YAML map of camera_info keys");

  static const std::set<std::string> kKeys = {
      "image_width",          "image_height",         "camera_name",
      "camera_matrix",        "distortion_model",     "distortion_coefficients",
      "rectification_matrix", "projection_matrix"};
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (kKeys.count(key) == 0) {
      Fail(source, kv.first,
           "unknown key '" + key +
               "' (expected image_width, image_height, camera_name, camera_matrix, "
               "distortion_model, distortion_coefficients, rectification_matrix, "
               "projection_matrix)");
    }
  }
  for (const char* key : {"image_width", "image_height", "camera_matrix"}) {
    if (!root[key]) Fail(source, root, std::string("missing required key '") + key + "'");
  }

  CameraInfo info;
  info.image_width = Scalar<int>(root["image_width"], "image_width", source);
  info.image_height = Scalar<int>(root["image_height"], "image_height", source);
  if (root["camera_name"]) {
    info.camera_name = Scalar<std::string>(root["camera_name"], "camera_name", source);
  }
  const std::vector<double> k = ReadMatrix(root["camera_matrix"], "camera_matrix", 3, 3, source);
  std::copy(k.begin(), k.end(), info.camera_matrix.begin());

  if (root["distortion_model"]) {
    info.distortion_model =
        Scalar<std::string>(root["distortion_model"], "distortion_model", source);
  }
  if (root["distortion_coefficients"]) {
    info.distortion_coefficients =
        ReadMatrix(root["distortion_coefficients"], "distortion_coefficients", 1, -1, source);
  } else {
    // Absent D means an undistorted camera of the model (ROS writes zeros).
    auto it = DistortionCounts().find(info.distortion_model);
    info.distortion_coefficients.assign(it == DistortionCounts().end() ? 5 : it->second, 0.0);
  }
  if (root["rectification_matrix"]) {
    const auto r = ReadMatrix(root["rectification_matrix"], "rectification_matrix", 3, 3, source);
    std::copy(r.begin(), r.end(), info.rectification_matrix.begin());
  }
  if (root["projection_matrix"]) {
    const auto p = ReadMatrix(root["projection_matrix"], "projection_matrix", 3, 4, source);
    std::copy(p.begin(), p.end(), info.projection_matrix.begin());
  } else {
    // A monocular camera without rectification: P = [K | 0].
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) info.projection_matrix[r * 4 + c] = info.camera_matrix[r * 3 + c];
      info.projection_matrix[r * 4 + 3] = 0.0;
    }
  }

  try {
    info.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(source + ": camera_info: " + e.what());
  }
  return info;
}

std::string CameraInfo::ToYamlString() const {
  std::ostringstream out;
  out << "image_width: " << image_width << "\n";
  out << "image_height: " << image_height << "\n";
  // Quoted so names such as "yes" or "1" read back as strings.
  out << "camera_name: " << YAML::Dump(YAML::Node(camera_name)) << "\n";
  WriteMatrix(out, "camera_matrix", 3, 3, camera_matrix.data());
  out << "distortion_model: " << distortion_model << "\n";
  WriteMatrix(out, "distortion_coefficients", 1, static_cast<int>(distortion_coefficients.size()),
              distortion_coefficients.data());
  WriteMatrix(out, "rectification_matrix", 3, 3, rectification_matrix.data());
  WriteMatrix(out, "projection_matrix", 3, 4, projection_matrix.data());
  return out.str();
}

void CameraInfo::ToYamlFile(const std::string& path) const {
  try {
    Validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("camera_info: refusing to write '" + path + "': " + e.what());
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error("camera_info: cannot write '" + tmp + "'");
    out << ToYamlString();
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error("camera_info: write to '" + tmp + "' failed (disk full?)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("camera_info: cannot rename '" + tmp + "' to '" + path + "'");
  }
}

void CameraInfo::Validate() const {
  const std::string who = "camera '" + camera_name + "': ";
  if (image_width <= 0 || image_height <= 0) {
    throw std::invalid_argument(who + "image size " + std::to_string(image_width) + "x" +
                                std::to_string(image_height) + " must be positive");
  }
  if (!AllFinite(camera_matrix) || !AllFinite(rectification_matrix) ||
      !AllFinite(projection_matrix)) {
    throw std::invalid_argument(who + "camera, rectification or projection matrix has a "
                                      "non-finite value");
  }
  for (double d : distortion_coefficients) {
    if (!std::isfinite(d)) throw std::invalid_argument(who + "non-finite distortion coefficient");
  }
  if (!(fx() > 0.0) || !(fy() > 0.0)) {
    throw std::invalid_argument(who + "focal lengths fx=" + FormatDouble(fx()) +
                                " fy=" + FormatDouble(fy()) + " must be positive");
  }
  if (camera_matrix[3] != 0.0 || camera_matrix[6] != 0.0 || camera_matrix[7] != 0.0 ||
      camera_matrix[8] != 1.0) {
    throw std::invalid_argument(who + "camera_matrix must be [fx s cx; 0 fy cy; 0 0 1]");
  }
  // Pixel centres are at integers, so the image spans [-0.5, size - 0.5].
  if (cx() < -0.5 || cx() > image_width - 0.5 || cy() < -0.5 || cy() > image_height - 0.5) {
    throw std::invalid_argument(who + "principal point (" + FormatDouble(cx()) + ", " +
                                FormatDouble(cy()) + ") lies outside the " +
                                std::to_string(image_width) + "x" +
                                std::to_string(image_height) + " image");
  }
  const auto it = DistortionCounts().find(distortion_model);
  if (it == DistortionCounts().end()) {
    throw std::invalid_argument(who + "unknown distortion_model '" + distortion_model +
                                "' (use plumb_bob, rational_polynomial or equidistant)");
  }
  if (static_cast<int>(distortion_coefficients.size()) != it->second) {
    throw std::invalid_argument(who + "distortion_model " + distortion_model + " needs " +
                                std::to_string(it->second) + " coefficients, got " +
                                std::to_string(distortion_coefficients.size()));
  }
  if (!(projection_matrix[0] > 0.0) || !(projection_matrix[5] > 0.0) ||
      projection_matrix[10] != 1.0) {
    throw std::invalid_argument(who + "projection_matrix must have positive focal lengths and "
                                      "P[2][2] = 1");
  }
}

CameraInfo CameraInfo::Scaled(int new_width, int new_height) const {
  if (new_width <= 0 || new_height <= 0) {
    throw std::invalid_argument("CameraInfo::Scaled: size " + std::to_string(new_width) + "x" +
                                std::to_string(new_height) + " must be positive");
  }
  if (image_width <= 0 || image_height <= 0) {
    throw std::invalid_argument("CameraInfo::Scaled: camera '" + camera_name +
                                "' has no image size");
  }
  const double sx = static_cast<double>(new_width) / image_width;
  const double sy = static_cast<double>(new_height) / image_height;
  CameraInfo out = *this;
  out.image_width = new_width;
  out.image_height = new_height;
  ScaleRow(&out.camera_matrix[0], sx, 3);
  ScaleRow(&out.camera_matrix[3], sy, 3);
  ScaleRow(&out.projection_matrix[0], sx, 4);
  ScaleRow(&out.projection_matrix[4], sy, 4);
  // Distortion acts on normalised coordinates and R on rays: neither depends on pixel size.
  return out;
}

CameraInfo CameraInfo::Cropped(int x0, int y0, int width, int height) const {
  if (x0 < 0 || y0 < 0 || width <= 0 || height <= 0 || x0 + width > image_width ||
      y0 + height > image_height) {
    throw std::invalid_argument("CameraInfo::Cropped: crop " + std::to_string(width) + "x" +
                                std::to_string(height) + "+" + std::to_string(x0) + "+" +
                                std::to_string(y0) + " does not fit the " +
                                std::to_string(image_width) + "x" +
                                std::to_string(image_height) + " image of camera '" +
                                camera_name + "'");
  }
  CameraInfo out = *this;
  out.image_width = width;
  out.image_height = height;
  out.camera_matrix[2] -= x0;
  out.camera_matrix[5] -= y0;
  out.projection_matrix[2] -= x0;
  out.projection_matrix[6] -= y0;
  // An off-centre crop may legitimately move the principal point out of the image, so the
  // result is not Validate()d here.
  return out;
}

bool CameraInfo::equals(const CameraInfo& other, double tol) const {
  if (camera_name != other.camera_name || image_width != other.image_width ||
      image_height != other.image_height || distortion_model != other.distortion_model ||
      distortion_coefficients.size() != other.distortion_coefficients.size()) {
    return false;
  }
  for (size_t i = 0; i < distortion_coefficients.size(); ++i) {
    if (!(std::abs(distortion_coefficients[i] - other.distortion_coefficients[i]) <= tol)) {
      return false;
    }
  }
  return Near(camera_matrix, other.camera_matrix, tol) &&
         Near(rectification_matrix, other.rectification_matrix, tol) &&
         Near(projection_matrix, other.projection_matrix, tol);
}

}  // namespace p2i::scene
