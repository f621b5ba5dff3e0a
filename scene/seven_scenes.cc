/// @file seven_scenes.cc
/// @brief 7-Scenes reader: seq-XX/frame-NNNNNN.{color.png,depth.png,pose.txt}.
#include "scene/seven_scenes.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace p2i::scene {
namespace {

namespace fs = std::filesystem;

bool HasFrames(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("frame-", 0) == 0 && name.size() > 9 &&
        name.compare(name.size() - 9, 9, ".pose.txt") == 0) {
      return true;
    }
  }
  return false;
}

/// Frame numbers of dir's frame-NNNNNN.pose.txt files, sorted.
std::vector<std::pair<long, std::string>> ListFrames(const fs::path& dir) {
  static const std::regex kPose(R"(frame-(\d+)\.pose\.txt)");
  std::vector<std::pair<long, std::string>> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    std::smatch m;
    if (std::regex_match(name, m, kPose)) {
      out.emplace_back(std::stol(m[1].str()), name.substr(0, name.size() - 9));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

void SevenScenesOptions::Validate() const {
  if (!(depth.scale > 0.0) || !std::isfinite(depth.scale)) {
    throw std::invalid_argument("SevenScenesOptions: depth.scale must be positive and finite");
  }
  if (!(frame_rate > 0.0) || !std::isfinite(frame_rate)) {
    throw std::invalid_argument("SevenScenesOptions: frame_rate must be positive and finite");
  }
}

Pose ReadSevenScenesPose(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open pose file '" + path + "'");
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      std::string token;
      if (!(in >> token)) {
        throw std::runtime_error("pose file '" + path + "' has fewer than 16 numbers (a 4x4 "
                                 "camera-to-world matrix is expected)");
      }
      try {
        size_t used = 0;
        m(r, c) = std::stod(token, &used);
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw std::runtime_error("pose file '" + path + "': '" + token + "' is not a number");
      }
    }
  }
  try {
    return Pose::FromMatrix(m);
  } catch (const std::exception& e) {
    throw std::runtime_error("pose file '" + path + "': " + e.what());
  }
}

CameraInfo ReadIntrinsicsMatrixFile(const std::string& path, int width, int height) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open intrinsics file '" + path + "'");
  double k[9];
  for (double& v : k) {
    if (!(in >> v)) {
      throw std::runtime_error("intrinsics file '" + path + "' must hold 9 numbers (3x3 K)");
    }
  }
  return CameraInfo::Pinhole(width, height, k[0], k[4], k[2], k[5]);
}

namespace {

/// Which sequence folders: options.sequences when given, else the root itself when it holds
/// frames, else its seq-* children (sorted).
std::vector<fs::path> SequenceDirs(const std::string& root, const SevenScenesOptions& options) {
  const fs::path root_path(root);
  std::vector<fs::path> seq_dirs;
  if (!options.sequences.empty()) {
    for (const std::string& s : options.sequences) {
      const fs::path p = root_path / s;
      if (!fs::is_directory(p)) {
        throw std::runtime_error("7-Scenes sequence folder '" + p.string() + "' does not exist");
      }
      seq_dirs.push_back(p);
    }
  } else if (HasFrames(root_path)) {
    seq_dirs.push_back(root_path);
  } else {
    for (const auto& e : fs::directory_iterator(root_path)) {
      if (e.is_directory() && e.path().filename().string().rfind("seq-", 0) == 0) {
        seq_dirs.push_back(e.path());
      }
    }
    std::sort(seq_dirs.begin(), seq_dirs.end());
  }
  if (seq_dirs.empty()) {
    throw std::runtime_error("7-Scenes folder '" + root +
                             "' has no seq-* folders and no frame-*.pose.txt files");
  }
  return seq_dirs;
}

/// One sequence folder's frames in frame-number order, each with its pose read and its colour
/// and depth files checked to exist.
std::vector<FrameRef> ReadSequenceFrames(const fs::path& dir, double frame_rate) {
  const std::string seq = fs::absolute(dir).lexically_normal().filename().string();
  const auto list = ListFrames(dir);
  if (list.empty()) {
    throw std::runtime_error("7-Scenes sequence '" + dir.string() +
                             "' has no frame-NNNNNN.pose.txt files");
  }
  std::vector<FrameRef> frames;
  for (const auto& [number, stem] : list) {
    FrameRef f;
    f.sequence = seq;
    f.id = seq + "/" + stem;
    f.stamp = static_cast<double>(number) / frame_rate;
    f.pose = ReadSevenScenesPose((dir / (stem + ".pose.txt")).string());
    f.rgb_path = (dir / (stem + ".color.png")).string();
    f.depth_path = (dir / (stem + ".depth.png")).string();
    for (const std::string& p : {f.rgb_path, f.depth_path}) {
      if (!fs::exists(p)) {
        throw std::runtime_error("7-Scenes frame '" + f.id + "' has a pose but no '" + p + "'");
      }
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

/// The calibration: options.camera_info_file, else root/camera_info.yaml, else
/// root/camera-intrinsics.txt, else the dataset's nominal 585 px pinhole; its size must match
/// the first colour image's pixels (one decode; calibration files may omit the size).
CameraInfo SevenScenesCamera(const std::string& root, const SevenScenesOptions& options,
                             const std::string& first_rgb_path) {
  const cv::Mat first = cv::imread(first_rgb_path, cv::IMREAD_COLOR);
  if (first.empty()) {
    throw std::runtime_error("cannot read colour image '" + first_rgb_path + "'");
  }
  const fs::path root_path(root);
  CameraInfo camera;
  const fs::path yaml = root_path / "camera_info.yaml";
  const fs::path txt = root_path / "camera-intrinsics.txt";
  if (!options.camera_info_file.empty()) {
    camera = CameraInfo::FromYamlFile(options.camera_info_file);
  } else if (fs::exists(yaml)) {
    camera = CameraInfo::FromYamlFile(yaml.string());
  } else if (fs::exists(txt)) {
    camera = ReadIntrinsicsMatrixFile(txt.string(), first.cols, first.rows);
  } else {
    camera = CameraInfo::Pinhole(first.cols, first.rows, 585.0, 585.0, first.cols / 2.0,
                                 first.rows / 2.0, "seven_scenes");
  }
  if (camera.image_width != first.cols || camera.image_height != first.rows) {
    throw std::runtime_error("calibration for '" + root + "' is for " +
                             std::to_string(camera.image_width) + "x" +
                             std::to_string(camera.image_height) + " but '" + first_rgb_path +
                             "' is " + std::to_string(first.cols) + "x" +
                             std::to_string(first.rows));
  }
  return camera;
}

}  // namespace

DatasetIndex ReadSevenScenes(const std::string& root, const SevenScenesOptions& options) {
  options.Validate();
  const fs::path root_path(root);
  if (!fs::is_directory(root_path)) {
    throw std::runtime_error("7-Scenes folder '" + root + "' does not exist or is not a folder");
  }
  std::vector<FrameRef> frames;
  for (const fs::path& dir : SequenceDirs(root, options)) {
    std::vector<FrameRef> seq = ReadSequenceFrames(dir, options.frame_rate);
    std::move(seq.begin(), seq.end(), std::back_inserter(frames));
  }
  const CameraInfo camera = SevenScenesCamera(root, options, frames.front().rgb_path);
  return DatasetIndex(camera, options.depth, std::move(frames));
}

}  // namespace p2i::scene
