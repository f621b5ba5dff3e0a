/// @file capture.cc
/// @brief p2i capture folder writer and reader.
#include "scene/capture.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

namespace p2i::scene {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFormat = "p2i_capture";
constexpr int kVersion = 1;

std::string FrameName(size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06zu", index);
  return buf;
}

std::string StampText(double stamp) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6f", stamp);
  return buf;
}

std::string EncodePng(const cv::Mat& image, const std::string& what) {
  std::vector<uchar> buf;
  if (!cv::imencode(".png", image, buf)) {
    throw std::runtime_error("capture: PNG encoding failed for " + what);
  }
  return std::string(buf.begin(), buf.end());
}

void WriteAll(int fd, const std::string& bytes, const std::string& path) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
    }
    done += static_cast<size_t>(n);
  }
}

}  // namespace

void WriteFileAtomic(const std::string& path, const std::string& bytes, bool sync) {
  static std::atomic<unsigned> counter{0};
  const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + "." +
                          std::to_string(counter.fetch_add(1));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw std::runtime_error("cannot create '" + tmp + "': " + std::strerror(errno) +
                             " (is the folder writable?)");
  }
  try {
    WriteAll(fd, bytes, tmp);
    if (sync && ::fsync(fd) != 0) {
      throw std::runtime_error("fsync of '" + tmp + "' failed: " + std::strerror(errno));
    }
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string err = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "': " + err);
  }
}

CaptureWriter::CaptureWriter(const std::string& folder, const CameraInfo& camera,
                             const Options& options)
    : folder_(folder), camera_(camera), options_(options) {
  camera_.Validate();
  const fs::path dir(folder);
  if (fs::exists(dir / "manifest.yaml") && !options_.overwrite) {
    throw std::runtime_error("capture folder '" + folder +
                             "' already holds a capture (manifest.yaml); choose another folder "
                             "or allow overwriting");
  }
  std::error_code ec;
  fs::create_directories(dir / "rgb", ec);
  if (!ec) fs::create_directories(dir / "depth", ec);
  if (ec) {
    throw std::runtime_error("cannot create capture folder '" + folder + "': " + ec.message());
  }
  WriteFileAtomic((dir / "camera_info.yaml").string(), camera_.ToYamlString(), options_.sync);
  Commit();
}

void CaptureWriter::Append(const RgbdSample& sample) {
  const auto check = [&](const cv::Mat& m, int type, const char* what) {
    if (m.type() != type || m.cols != camera_.image_width || m.rows != camera_.image_height) {
      throw std::invalid_argument(
          std::string("CaptureWriter::Append: ") + what + " of frame '" + sample.id + "' is " +
          std::to_string(m.cols) + "x" + std::to_string(m.rows) + " type " +
          std::to_string(m.type()) + "; expected " + std::to_string(camera_.image_width) + "x" +
          std::to_string(camera_.image_height) + " type " + std::to_string(type));
    }
  };
  check(sample.rgb, CV_8UC3, "rgb");
  check(sample.depth, CV_32FC1, "depth");
  if (!std::isfinite(sample.stamp)) {
    throw std::invalid_argument("CaptureWriter::Append: non-finite stamp");
  }
  const std::string name = FrameName(count_) + ".png";
  const fs::path dir(folder_);
  cv::Mat bgr;
  cv::cvtColor(sample.rgb, bgr, cv::COLOR_RGB2BGR);
  WriteFileAtomic((dir / "rgb" / name).string(), EncodePng(bgr, "rgb " + name), options_.sync);
  WriteFileAtomic((dir / "depth" / name).string(),
                  EncodePng(DepthToMillimetres(sample.depth), "depth " + name), options_.sync);
  const std::string stamp = StampText(sample.stamp);
  poses_ += sample.pose.ToTumLine(std::stod(stamp)) + "\n";
  manifest_frames_ += "  - {index: " + std::to_string(count_) + ", stamp: " + stamp +
                      ", rgb: rgb/" + name + ", depth: depth/" + name + "}\n";
  ++count_;
  Commit();
}

void CaptureWriter::Commit() {
  const fs::path dir(folder_);
  // poses.txt first: it may then hold one line more than the manifest lists, which the reader
  // ignores; the manifest never lists a frame whose pose is not yet written.
  WriteFileAtomic((dir / "poses.txt").string(), "# timestamp tx ty tz qx qy qz qw\n" + poses_,
                  options_.sync);
  std::ostringstream m;
  m << "# p2i capture folder, see docs/DATASETS.md\n"
    << "format: " << kFormat << "\n"
    << "version: " << kVersion << "\n"
    << "camera_info: camera_info.yaml\n"
    << "poses: poses.txt\n"
    << "depth: {scale: 0.001, invalid: 0}\n"
    << "frame_count: " << count_ << "\n"
    << "frames:" << (count_ == 0 ? " []\n" : "\n") << manifest_frames_;
  WriteFileAtomic((dir / "manifest.yaml").string(), m.str(), options_.sync);
}

bool IsCaptureFolder(const std::string& folder) {
  const fs::path manifest = fs::path(folder) / "manifest.yaml";
  if (!fs::exists(manifest)) return false;
  try {
    const YAML::Node root = YAML::LoadFile(manifest.string());
    return root["format"] && root["format"].as<std::string>() == kFormat;
  } catch (const std::exception&) {
    return false;
  }
}

namespace {

/// root[key], or an error naming the manifest and the missing key.
YAML::Node RequireKey(const YAML::Node& root, const std::string& manifest_path, const char* key) {
  if (!root[key]) {
    throw std::runtime_error("'" + manifest_path + "': missing key '" + key + "'");
  }
  return root[key];
}

/// The parsed manifest.yaml of `folder`: only known keys, this format, this version.
YAML::Node LoadCaptureManifest(const std::string& folder, const std::string& manifest_path) {
  if (!fs::exists(manifest_path)) {
    throw std::runtime_error("'" + folder + "' is not a p2i capture folder: no manifest.yaml");
  }
  YAML::Node root;
  try {
    root = YAML::LoadFile(manifest_path);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot parse '" + manifest_path + "': " + e.what());
  }
  const std::set<std::string> known = {"format", "version",     "camera_info", "poses",
                                       "depth",  "frame_count", "frames"};
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (known.count(key) == 0) {
      throw std::runtime_error("'" + manifest_path + "': unknown key '" + key + "'");
    }
  }
  if (RequireKey(root, manifest_path, "format").as<std::string>() != kFormat) {
    throw std::runtime_error("'" + manifest_path + "': format is '" +
                             root["format"].as<std::string>() + "', expected '" + kFormat + "'");
  }
  const int version = RequireKey(root, manifest_path, "version").as<int>();
  if (version != kVersion) {
    throw std::runtime_error("'" + manifest_path + "': version " + std::to_string(version) +
                             " is not supported (this build reads version " +
                             std::to_string(kVersion) + ")");
  }
  return root;
}

/// poses.txt (TUM lines, '#' comments): line k belongs to listed frame k.
std::vector<StampedPose> ReadCapturePoses(const std::string& poses_path) {
  std::vector<StampedPose> poses;
  std::ifstream in(poses_path);
  if (!in) throw std::runtime_error("cannot open '" + poses_path + "'");
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    StampedPose p;
    try {
      p.pose = Pose::FromTumLine(line, &p.stamp);
    } catch (const std::exception& e) {
      throw std::runtime_error("'" + poses_path + "' line " + std::to_string(number) + ": " +
                               e.what());
    }
    poses.push_back(p);
  }
  return poses;
}

/// The manifest's frame_count must be the number of entries in its 'frames'.
void CheckFrameCount(const YAML::Node& root, const std::string& manifest_path,
                     const YAML::Node& frames) {
  long long count = -1;
  try {
    count = RequireKey(root, manifest_path, "frame_count").as<long long>();
  } catch (const YAML::Exception&) {
  }
  if (count < 0 || static_cast<size_t>(count) != frames.size()) {
    throw std::runtime_error("'" + manifest_path + "': frame_count is " +
                             RequireKey(root, manifest_path, "frame_count").as<std::string>() +
                             " but 'frames' lists " + std::to_string(frames.size()) +
                             " (a damaged or hand-edited manifest; make them agree)");
  }
}

/// One FrameRef per listed frame, with pose k of poses.txt (its stamp must match) and the
/// image files checked to exist.
std::vector<FrameRef> CaptureFrameRefs(const fs::path& dir, const YAML::Node& frames,
                                       const std::vector<StampedPose>& poses,
                                       const std::string& manifest_path,
                                       const std::string& poses_path) {
  const std::string seq = fs::absolute(dir).lexically_normal().filename().string();
  std::vector<FrameRef> refs;
  for (size_t k = 0; k < frames.size(); ++k) {
    const YAML::Node f = frames[k];
    FrameRef r;
    r.sequence = seq;
    r.id = seq + "/" + FrameName(f["index"] ? f["index"].as<size_t>() : k);
    r.stamp = f["stamp"].as<double>();
    if (std::abs(poses[k].stamp - r.stamp) > 1e-6) {
      throw std::runtime_error("'" + poses_path + "': pose " + std::to_string(k) + " has stamp " +
                               std::to_string(poses[k].stamp) + " but the manifest lists " +
                               std::to_string(r.stamp));
    }
    r.pose = poses[k].pose;
    r.rgb_path = (dir / f["rgb"].as<std::string>()).string();
    r.depth_path = (dir / f["depth"].as<std::string>()).string();
    for (const std::string& p : {r.rgb_path, r.depth_path}) {
      if (!fs::exists(p)) {
        throw std::runtime_error("'" + manifest_path + "' lists '" + p + "', which is missing");
      }
    }
    refs.push_back(std::move(r));
  }
  return refs;
}

}  // namespace

DatasetIndex ReadCapture(const std::string& folder) {
  const fs::path dir(folder);
  const std::string manifest_path = (dir / "manifest.yaml").string();
  const YAML::Node root = LoadCaptureManifest(folder, manifest_path);
  DepthEncoding encoding;
  const YAML::Node depth = RequireKey(root, manifest_path, "depth");
  encoding.scale = depth["scale"] ? depth["scale"].as<double>() : 0.001;
  encoding.invalid_value = depth["invalid"] ? depth["invalid"].as<uint16_t>() : 0;
  const CameraInfo camera = CameraInfo::FromYamlFile(
      (dir / RequireKey(root, manifest_path, "camera_info").as<std::string>()).string());
  const std::string poses_path =
      (dir / RequireKey(root, manifest_path, "poses").as<std::string>()).string();
  const std::vector<StampedPose> poses = ReadCapturePoses(poses_path);
  const YAML::Node frames = RequireKey(root, manifest_path, "frames");
  CheckFrameCount(root, manifest_path, frames);
  if (frames.size() > poses.size()) {
    throw std::runtime_error("'" + poses_path + "' has " + std::to_string(poses.size()) +
                             " poses but '" + manifest_path + "' lists " +
                             std::to_string(frames.size()) + " frames");
  }
  return DatasetIndex(camera, encoding, CaptureFrameRefs(dir, frames, poses, manifest_path,
                                                         poses_path));
}

}  // namespace p2i::scene
