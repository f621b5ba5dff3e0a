/// @file tum_rgbd.cc
/// @brief TUM RGB-D reader with timestamp association and SLERP-interpolated ground truth.
#include "scene/tum_rgbd.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include <opencv2/imgcodecs.hpp>

#include "scene/trajectory_io.h"

namespace p2i::scene {
namespace {

namespace fs = std::filesystem;

struct StampedFile {
  double stamp = 0.0;
  std::string stamp_text;
  std::string path;
};

/// Reads "stamp filename" lines; '#' starts a comment.
std::vector<StampedFile> ReadFileList(const fs::path& list, const fs::path& folder) {
  std::ifstream in(list);
  if (!in) throw std::runtime_error("TUM RGB-D: cannot open '" + list.string() + "'");
  std::vector<StampedFile> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream ss(line);
    StampedFile f;
    std::string file;
    if (!(ss >> f.stamp_text >> file)) {
      throw std::runtime_error("TUM RGB-D: '" + list.string() + "' line " +
                               std::to_string(number) + ": expected 'timestamp filename'");
    }
    try {
      f.stamp = std::stod(f.stamp_text);
    } catch (const std::exception&) {
      throw std::runtime_error("TUM RGB-D: '" + list.string() + "' line " +
                               std::to_string(number) + ": '" + f.stamp_text +
                               "' is not a timestamp");
    }
    f.path = (folder / file).string();
    out.push_back(std::move(f));
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedFile& a, const StampedFile& b) { return a.stamp < b.stamp; });
  return out;
}

}  // namespace

void TumRgbdOptions::Validate() const {
  if (!(depth.scale > 0.0) || !std::isfinite(depth.scale)) {
    throw std::invalid_argument("TumRgbdOptions: depth.scale must be positive and finite");
  }
  if (!(max_difference >= 0.0) || !(max_pose_gap > 0.0)) {
    throw std::invalid_argument(
        "TumRgbdOptions: max_difference must be >= 0 and max_pose_gap > 0");
  }
}

std::vector<std::pair<size_t, size_t>> AssociateStamps(const std::vector<double>& a,
                                                       const std::vector<double>& b,
                                                       double max_difference) {
  // Candidates: for each a, the b's within the window (both sorted, so a sliding start).
  std::vector<std::tuple<double, size_t, size_t>> candidates;
  size_t lo = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    while (lo < b.size() && b[lo] < a[i] - max_difference) ++lo;
    for (size_t j = lo; j < b.size() && b[j] <= a[i] + max_difference; ++j) {
      candidates.emplace_back(std::abs(a[i] - b[j]), i, j);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<size_t, size_t>> out;
  for (const auto& [diff, i, j] : candidates) {
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = true;
    out.emplace_back(i, j);
  }
  std::sort(out.begin(), out.end());
  return out;
}

DatasetIndex ReadTumRgbd(const std::string& folder, const TumRgbdOptions& options, int* dropped) {
  options.Validate();
  const fs::path dir(folder);
  if (!fs::is_directory(dir)) {
    throw std::runtime_error("TUM RGB-D folder '" + folder + "' does not exist");
  }
  const auto rgb = ReadFileList(dir / "rgb.txt", dir);
  const auto depth = ReadFileList(dir / "depth.txt", dir);
  const auto truth = ReadTumTrajectory((dir / "groundtruth.txt").string(), TumStampOrder::kSort);
  std::vector<double> rgb_stamps, depth_stamps;
  for (const auto& f : rgb) rgb_stamps.push_back(f.stamp);
  for (const auto& f : depth) depth_stamps.push_back(f.stamp);
  const auto pairs = AssociateStamps(rgb_stamps, depth_stamps, options.max_difference);

  const std::string seq = fs::absolute(dir).lexically_normal().filename().string();
  std::vector<FrameRef> frames;
  for (const auto& [i, j] : pairs) {
    const auto pose = InterpolateAt(truth, rgb[i].stamp, options.max_pose_gap);
    if (!pose) continue;
    FrameRef f;
    f.sequence = seq;
    f.id = seq + "/" + rgb[i].stamp_text;
    f.stamp = rgb[i].stamp;
    f.pose = *pose;
    f.rgb_path = rgb[i].path;
    f.depth_path = depth[j].path;
    frames.push_back(std::move(f));
  }
  if (dropped != nullptr) *dropped = static_cast<int>(rgb.size() - frames.size());
  if (frames.empty()) {
    throw std::runtime_error("TUM RGB-D folder '" + folder + "': no rgb image has a depth image "
                             "within max_difference and a ground-truth pose; check the stamps");
  }

  CameraInfo camera;
  const fs::path yaml = dir / "camera_info.yaml";
  if (!options.camera_info_file.empty()) {
    camera = CameraInfo::FromYamlFile(options.camera_info_file);
  } else if (fs::exists(yaml)) {
    camera = CameraInfo::FromYamlFile(yaml.string());
  } else {
    const cv::Mat first = cv::imread(frames.front().rgb_path, cv::IMREAD_COLOR);
    if (first.empty()) {
      throw std::runtime_error("cannot read colour image '" + frames.front().rgb_path + "'");
    }
    const double sx = first.cols / 640.0, sy = first.rows / 480.0;
    camera = CameraInfo::Pinhole(first.cols, first.rows, 525.0 * sx, 525.0 * sy, 319.5 * sx,
                                 239.5 * sy, "tum_rgbd");
  }
  return DatasetIndex(camera, options.depth, std::move(frames));
}

}  // namespace p2i::scene
