/// @file dataset_index.cc
/// @brief Frame references and the image decoders shared by every dataset reader.
#include "scene/dataset_index.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace p2i::scene {

cv::Mat ReadRgbImage(const std::string& path) {
  cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) {
    throw std::runtime_error("cannot read colour image '" + path +
                             "': missing file or not an image OpenCV can decode");
  }
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

cv::Mat ReadDepthImage(const std::string& path, const DepthEncoding& encoding) {
  cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) {
    throw std::runtime_error("cannot read depth image '" + path +
                             "': missing file or not an image OpenCV can decode");
  }
  if (raw.type() != CV_16UC1) {
    throw std::runtime_error("depth image '" + path + "' has " + std::to_string(raw.channels()) +
                             " channel(s) of depth " + std::to_string(raw.depth()) +
                             " (OpenCV code); expected a 16-bit single-channel PNG");
  }
  cv::Mat depth(raw.size(), CV_32FC1);
  const float scale = static_cast<float>(encoding.scale);
  for (int r = 0; r < raw.rows; ++r) {
    const uint16_t* in = raw.ptr<uint16_t>(r);
    float* out = depth.ptr<float>(r);
    for (int c = 0; c < raw.cols; ++c) {
      const uint16_t v = in[c];
      out[c] = (v == 0 || v == encoding.invalid_value) ? 0.0f : static_cast<float>(v) * scale;
    }
  }
  return depth;
}

cv::Mat DepthToMillimetres(const cv::Mat& depth_m) {
  if (depth_m.type() != CV_32FC1) {
    throw std::invalid_argument("DepthToMillimetres: depth must be CV_32FC1 metres");
  }
  cv::Mat mm(depth_m.size(), CV_16UC1);
  for (int r = 0; r < depth_m.rows; ++r) {
    const float* in = depth_m.ptr<float>(r);
    uint16_t* out = mm.ptr<uint16_t>(r);
    for (int c = 0; c < depth_m.cols; ++c) {
      const float d = in[c];
      const double v = std::isfinite(d) && d > 0.0f ? std::round(d * 1000.0) : 0.0;
      out[c] = (v >= 1.0 && v <= 65534.0) ? static_cast<uint16_t>(v) : 0;
    }
  }
  return mm;
}

DatasetIndex::DatasetIndex(CameraInfo camera, DepthEncoding encoding, std::vector<FrameRef> frames)
    : camera_(std::move(camera)), encoding_(encoding), frames_(std::move(frames)) {}

RgbdSample DatasetIndex::Load(size_t i) const {
  if (i >= frames_.size()) {
    throw std::out_of_range("DatasetIndex::Load: frame " + std::to_string(i) + " of " +
                            std::to_string(frames_.size()));
  }
  const FrameRef& f = frames_[i];
  RgbdSample s;
  s.stamp = f.stamp;
  s.pose = f.pose;
  s.id = f.id;
  s.rgb = ReadRgbImage(f.rgb_path);
  s.depth = ReadDepthImage(f.depth_path, encoding_);
  const auto check = [&](const cv::Mat& m, const std::string& path) {
    if (camera_.image_width > 0 &&
        (m.cols != camera_.image_width || m.rows != camera_.image_height)) {
      throw std::runtime_error("image '" + path + "' is " + std::to_string(m.cols) + "x" +
                               std::to_string(m.rows) + " but the dataset's camera is " +
                               std::to_string(camera_.image_width) + "x" +
                               std::to_string(camera_.image_height));
    }
  };
  check(s.rgb, f.rgb_path);
  check(s.depth, f.depth_path);
  return s;
}

RgbdDataset DatasetIndex::LoadAll() const {
  RgbdDataset d;
  d.camera = camera_;
  d.frames.reserve(frames_.size());
  for (size_t i = 0; i < frames_.size(); ++i) d.frames.push_back(Load(i));
  return d;
}

std::vector<std::string> DatasetIndex::Sequences() const {
  std::vector<std::string> out;
  std::unordered_set<std::string> seen;
  for (const FrameRef& f : frames_) {
    if (seen.insert(f.sequence).second) out.push_back(f.sequence);
  }
  return out;
}

DatasetIndex DatasetIndex::SelectSequences(const std::vector<std::string>& sequences) const {
  const std::unordered_set<std::string> wanted(sequences.begin(), sequences.end());
  const std::vector<std::string> have = Sequences();
  for (const std::string& s : sequences) {
    if (std::find(have.begin(), have.end(), s) == have.end()) {
      std::string list;
      for (const std::string& h : have) list += (list.empty() ? "" : ", ") + h;
      throw std::invalid_argument("sequence '" + s + "' is not in the dataset (it has: " + list +
                                  ")");
    }
  }
  std::vector<FrameRef> out;
  for (const FrameRef& f : frames_) {
    if (wanted.count(f.sequence) != 0) out.push_back(f);
  }
  return DatasetIndex(camera_, encoding_, std::move(out));
}

DatasetIndex DatasetIndex::SelectIds(const std::vector<std::string>& ids) const {
  std::unordered_map<std::string, size_t> by_id;
  for (size_t i = 0; i < frames_.size(); ++i) by_id.emplace(frames_[i].id, i);
  std::vector<FrameRef> out;
  out.reserve(ids.size());
  for (const std::string& id : ids) {
    const auto it = by_id.find(id);
    if (it == by_id.end()) {
      throw std::invalid_argument("frame id '" + id + "' is not in the dataset");
    }
    out.push_back(frames_[it->second]);
  }
  return DatasetIndex(camera_, encoding_, std::move(out));
}

int DatasetIndex::Find(const std::string& id) const {
  for (size_t i = 0; i < frames_.size(); ++i) {
    if (frames_[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace p2i::scene
