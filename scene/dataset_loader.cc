/// @file dataset_loader.cc
/// @brief Format detection and multi-sequence concatenation.
#include "scene/dataset_loader.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "scene/capture.h"
#include "scene/seven_scenes.h"
#include "scene/tum_rgbd.h"

namespace p2i::scene {
namespace {

namespace fs = std::filesystem;

bool IsTumFolder(const fs::path& p) {
  return fs::exists(p / "rgb.txt") && fs::exists(p / "depth.txt");
}

std::vector<fs::path> SubFolders(const fs::path& p, bool (*pred)(const fs::path&)) {
  std::vector<fs::path> out;
  if (!fs::is_directory(p)) return out;
  for (const auto& e : fs::directory_iterator(p)) {
    if (e.is_directory() && pred(e.path())) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool IsCapturePath(const fs::path& p) { return IsCaptureFolder(p.string()); }

bool HasSevenScenesFrames(const fs::path& p) {
  for (const auto& e : fs::directory_iterator(p)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("frame-", 0) == 0 && n.find(".pose.txt") != std::string::npos) return true;
  }
  return false;
}

DatasetIndex Concatenate(const std::vector<DatasetIndex>& parts, const std::string& path) {
  std::vector<FrameRef> frames;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (!parts[i].camera().equals(parts[0].camera(), 1e-6)) {
      throw std::runtime_error("dataset '" + path + "': sequence '" +
                               parts[i].frames().front().sequence +
                               "' has a different calibration from '" +
                               parts[0].frames().front().sequence +
                               "'; open the sequences separately");
    }
    frames.insert(frames.end(), parts[i].frames().begin(), parts[i].frames().end());
  }
  return DatasetIndex(parts[0].camera(), parts[0].depth_encoding(), std::move(frames));
}

}  // namespace

void DatasetOptions::Validate() const {
  if (format != "auto" && format != "capture" && format != "tum" && format != "7scenes") {
    throw std::invalid_argument("dataset format '" + format +
                                "' is unknown (use auto, capture, tum or 7scenes)");
  }
  if (seven_scenes_invalid_depth < 0 || seven_scenes_invalid_depth > 65535) {
    throw std::invalid_argument("seven_scenes_invalid_depth must be in [0, 65535]");
  }
}

std::string DetectDatasetFormat(const std::string& path) {
  const fs::path p(path);
  if (!fs::is_directory(p)) return "";
  if (IsCapturePath(p) || !SubFolders(p, IsCapturePath).empty()) return "capture";
  if (IsTumFolder(p) || !SubFolders(p, IsTumFolder).empty()) return "tum";
  if (HasSevenScenesFrames(p) || !SubFolders(p, HasSevenScenesFrames).empty()) return "7scenes";
  return "";
}

DatasetIndex OpenDataset(const std::string& path, const DatasetOptions& options) {
  options.Validate();
  if (!fs::is_directory(path)) {
    throw std::runtime_error("dataset folder '" + path + "' does not exist");
  }
  const std::string format =
      options.format == "auto" ? DetectDatasetFormat(path) : options.format;
  const fs::path p(path);
  DatasetIndex index;
  if (format == "capture") {
    if (IsCapturePath(p)) {
      index = ReadCapture(path);
    } else {
      std::vector<DatasetIndex> parts;
      for (const fs::path& sub : SubFolders(p, IsCapturePath)) {
        parts.push_back(ReadCapture(sub.string()));
      }
      if (parts.empty()) throw std::runtime_error("'" + path + "' holds no p2i capture folder");
      index = Concatenate(parts, path);
    }
  } else if (format == "tum") {
    TumRgbdOptions o;
    o.max_difference = options.tum_max_difference;
    o.max_pose_gap = options.tum_max_pose_gap;
    o.camera_info_file = options.camera_info_file;
    if (IsTumFolder(p)) {
      index = ReadTumRgbd(path, o);
    } else {
      std::vector<DatasetIndex> parts;
      for (const fs::path& sub : SubFolders(p, IsTumFolder)) {
        parts.push_back(ReadTumRgbd(sub.string(), o));
      }
      if (parts.empty()) throw std::runtime_error("'" + path + "' holds no TUM RGB-D sequence");
      index = Concatenate(parts, path);
    }
  } else if (format == "7scenes") {
    SevenScenesOptions o;
    o.depth.invalid_value = static_cast<uint16_t>(options.seven_scenes_invalid_depth);
    o.camera_info_file = options.camera_info_file;
    index = ReadSevenScenes(path, o);
  } else {
    throw std::runtime_error(
        "'" + path + "' is not a dataset this build reads: expected a p2i capture folder "
        "(manifest.yaml), a TUM RGB-D folder (rgb.txt, depth.txt, groundtruth.txt) or a 7-Scenes "
        "folder (seq-XX/frame-NNNNNN.pose.txt); see docs/DATASETS.md");
  }
  if (!options.camera_info_file.empty() && format == "capture") {
    index = DatasetIndex(CameraInfo::FromYamlFile(options.camera_info_file),
                         index.depth_encoding(), index.frames());
  }
  return index;
}

}  // namespace p2i::scene
