/// @file tum_sequence_writer.cc
/// @brief Crash-safe TUM RGB-D sequence writer.
#include "nodes/slam_sink/tum_sequence_writer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace p2i::slam_sink {
namespace {

namespace fs = std::filesystem;

std::string ErrnoText() { return std::strerror(errno); }

std::string FormatStamp(double stamp) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6f", stamp);
  return buf;
}

std::string FormatNumber(double value) {
  if (!std::isfinite(value)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", value);
  return buf;
}

// Writes all of `size` bytes; false (errno set) on failure.
bool WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

void TumSequenceWriterOptions::Validate() const {
  if (out_dir.empty()) {
    throw std::invalid_argument("TumSequenceWriterOptions: out_dir is empty; set the folder the "
                                "TUM sequence is written to");
  }
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale)) {
    throw std::invalid_argument("TumSequenceWriterOptions: depth_scale must be positive and "
                                "finite (TUM uses 5000 units per metre), got " +
                                std::to_string(depth_scale));
  }
  if (png_compression < 0 || png_compression > 9) {
    throw std::invalid_argument("TumSequenceWriterOptions: png_compression must be in 0..9, got " +
                                std::to_string(png_compression));
  }
}

TumSequenceWriter::TumSequenceWriter(TumSequenceWriterOptions options)
    : options_(std::move(options)) {
  options_.Validate();
  const fs::path root(options_.out_dir);
  std::error_code ec;
  for (const char* sub : {"rgb", "depth"}) {
    fs::create_directories(root / sub, ec);
    if (ec) {
      throw std::runtime_error("TumSequenceWriter: cannot create folder '" +
                               (root / sub).string() + "': " + ec.message());
    }
  }
  if (!options_.append && fs::exists(root / rgb_index_.name) &&
      fs::file_size(root / rgb_index_.name) > 0) {
    throw std::runtime_error("TumSequenceWriter: '" + (root / rgb_index_.name).string() +
                             "' already exists; choose an empty out_dir or set append");
  }
  if (options_.append) {
    // Names already on disk must not be reused.
    for (const char* sub : {"rgb", "depth"}) {
      for (const auto& entry : fs::directory_iterator(root / sub)) {
        used_names_.insert(entry.path().stem().string());
      }
    }
  }
  OpenIndex(&rgb_index_,
            "# color images\n# file: 'p2i slam_sink'\n# timestamp filename\n");
  OpenIndex(&depth_index_,
            "# depth maps\n# file: 'p2i slam_sink'\n# timestamp filename\n");
  OpenIndex(&groundtruth_index_,
            "# ground truth trajectory (requested poses, camera-to-world)\n"
            "# file: 'p2i slam_sink'\n# timestamp tx ty tz qx qy qz qw\n");
  if (options_.write_associations) OpenIndex(&associations_index_, "");
  OpenIndex(&frames_index_,
            "# p2i slam_sink frames\n"
            "# timestamp source seq kind check t_err_m r_err_deg coverage rgb_file\n");
}

TumSequenceWriter::~TumSequenceWriter() {
  try {
    Close();
  } catch (...) {
    // A destructor must not throw; Close() is public for callers who want the error.
  }
  for (IndexFile* index : {&rgb_index_, &depth_index_, &groundtruth_index_, &associations_index_,
                           &frames_index_}) {
    if (index->fd >= 0) ::close(index->fd);
    index->fd = -1;
  }
}

void TumSequenceWriter::OpenIndex(IndexFile* index, const std::string& header) {
  const std::string path = (fs::path(options_.out_dir) / index->name).string();
  index->fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (index->fd < 0) {
    throw std::runtime_error("TumSequenceWriter: cannot open '" + path + "': " + ErrnoText());
  }
  struct stat st {};
  if (::fstat(index->fd, &st) == 0 && st.st_size == 0 && !header.empty()) {
    AppendLine(index, header.substr(0, header.size() - 1));  // header already ends in '\n'
  }
}

void TumSequenceWriter::AppendLine(IndexFile* index, const std::string& line) {
  // One write(2) per line on O_APPEND: a crash never leaves half a line behind (a regular file
  // write of a few hundred bytes is not split by a signal).
  const std::string text = line + "\n";
  if (!WriteAll(index->fd, text.data(), text.size())) {
    throw std::runtime_error("TumSequenceWriter: cannot append to '" +
                             (fs::path(options_.out_dir) / index->name).string() +
                             "': " + ErrnoText());
  }
}

std::string TumSequenceWriter::UniqueBaseName(double stamp, bool synthetic) {
  const std::string base = FormatStamp(stamp) + (synthetic ? "_syn" : "");
  std::string name = base;
  for (int i = 1; used_names_.count(name) > 0; ++i) name = base + "_" + std::to_string(i);
  used_names_.insert(name);
  return name;
}

void TumSequenceWriter::WriteFileAtomic(const std::string& relative_path,
                                        const std::vector<unsigned char>& bytes) {
  const fs::path final_path = fs::path(options_.out_dir) / relative_path;
  const fs::path temp_path =
      final_path.parent_path() / ("." + final_path.filename().string() + ".tmp");
  const int fd = ::open(temp_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw std::runtime_error("TumSequenceWriter: cannot create '" + temp_path.string() +
                             "': " + ErrnoText());
  }
  bool ok = WriteAll(fd, reinterpret_cast<const char*>(bytes.data()), bytes.size());
  if (ok && options_.fsync) ok = ::fsync(fd) == 0;
  const std::string write_error = ok ? "" : ErrnoText();
  ::close(fd);
  if (!ok) {
    ::unlink(temp_path.c_str());
    throw std::runtime_error("TumSequenceWriter: cannot write '" + temp_path.string() +
                             "': " + write_error + " (disk full?)");
  }
  if (::rename(temp_path.c_str(), final_path.c_str()) != 0) {
    const std::string err = ErrnoText();
    ::unlink(temp_path.c_str());
    throw std::runtime_error("TumSequenceWriter: cannot rename '" + temp_path.string() +
                             "' to '" + final_path.string() + "': " + err);
  }
}

cv::Mat TumSequenceWriter::DepthToUnits(const cv::Mat& depth_m, double scale,
                                        size_t* out_of_range) {
  CV_Assert(depth_m.type() == CV_32FC1);
  cv::Mat units(depth_m.size(), CV_16UC1);
  size_t bad = 0;
  for (int r = 0; r < depth_m.rows; ++r) {
    const float* in = depth_m.ptr<float>(r);
    uint16_t* out = units.ptr<uint16_t>(r);
    for (int c = 0; c < depth_m.cols; ++c) {
      const double d = in[c];
      if (!std::isfinite(d) || d <= 0.0) {
        out[c] = 0;
        continue;
      }
      const double u = std::round(d * scale);
      if (u > 65535.0) {
        out[c] = 0;  // saturating would write a wrong depth; invalid is the honest value
        ++bad;
      } else {
        out[c] = static_cast<uint16_t>(u);
      }
    }
  }
  if (out_of_range != nullptr) *out_of_range += bad;
  return units;
}

cv::Mat TumSequenceWriter::DepthFromUnits(const cv::Mat& depth_units, double scale) {
  CV_Assert(depth_units.type() == CV_16UC1);
  cv::Mat metres;
  depth_units.convertTo(metres, CV_32FC1, 1.0 / scale);
  return metres;
}

WrittenFiles TumSequenceWriter::Write(const SinkFrame& frame, const FrameRecord& record) {
  if (closed_) throw std::logic_error("TumSequenceWriter::Write after Close");
  if (frame.rgb.empty() || frame.rgb.type() != CV_8UC3) {
    throw std::invalid_argument("TumSequenceWriter::Write: rgb must be a non-empty CV_8UC3 image");
  }
  if (frame.depth.type() != CV_32FC1 || frame.depth.size() != frame.rgb.size()) {
    throw std::invalid_argument("TumSequenceWriter::Write: depth must be CV_32FC1 of the rgb size");
  }
  if (!std::isfinite(frame.stamp)) {
    throw std::invalid_argument("TumSequenceWriter::Write: the frame stamp is not finite");
  }
  const std::string base = UniqueBaseName(frame.stamp, frame.synthetic);
  WrittenFiles files{"rgb/" + base + ".png", "depth/" + base + ".png"};
  const std::vector<int> png_params{cv::IMWRITE_PNG_COMPRESSION, options_.png_compression};

  cv::Mat bgr;
  cv::cvtColor(frame.rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", bgr, bytes, png_params)) {
    throw std::runtime_error("TumSequenceWriter: PNG encoding failed for " + files.rgb);
  }
  WriteFileAtomic(files.rgb, bytes);
  const cv::Mat units = DepthToUnits(frame.depth, options_.depth_scale, &depth_out_of_range_);
  if (!cv::imencode(".png", units, bytes, png_params)) {
    throw std::runtime_error("TumSequenceWriter: PNG encoding failed for " + files.depth);
  }
  WriteFileAtomic(files.depth, bytes);

  // Both images exist under their final names: now (and only now) list them.
  const std::string stamp = FormatStamp(frame.stamp);
  AppendLine(&rgb_index_, stamp + " " + files.rgb);
  AppendLine(&depth_index_, stamp + " " + files.depth);
  if (frame.has_pose) AppendLine(&groundtruth_index_, frame.pose.ToTumLine(frame.stamp));
  if (options_.write_associations) {
    AppendLine(&associations_index_, stamp + " " + files.rgb + " " + stamp + " " + files.depth);
  }
  std::string source = frame.source.empty() ? "-" : frame.source;
  std::replace(source.begin(), source.end(), ' ', '_');
  AppendLine(&frames_index_, stamp + " " + source + " " + std::to_string(frame.seq) + " " +
                                 (frame.synthetic ? "synthetic" : "real") + " " + record.check +
                                 " " + FormatNumber(record.translation_error_m) + " " +
                                 FormatNumber(record.rotation_error_deg) + " " +
                                 FormatNumber(frame.coverage) + " " + files.rgb);
  if (options_.fsync) Flush();
  ++frames_written_;
  return files;
}

void TumSequenceWriter::Flush() {
  // Lines go straight to the kernel with write(2), so a process crash loses nothing; fsync
  // additionally survives a power loss.
  for (IndexFile* index : {&rgb_index_, &depth_index_, &groundtruth_index_, &associations_index_,
                           &frames_index_}) {
    if (index->fd >= 0) ::fsync(index->fd);
  }
}

void TumSequenceWriter::SortIndex(const IndexFile& index) {
  const fs::path path = fs::path(options_.out_dir) / index.name;
  std::ifstream in(path);
  if (!in) return;
  std::vector<std::string> comments;
  std::vector<std::pair<double, std::string>> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      comments.push_back(line);
      continue;
    }
    lines.emplace_back(std::strtod(line.c_str(), nullptr), line);
  }
  if (std::is_sorted(lines.begin(), lines.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; })) {
    return;
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::string text;
  for (const auto& c : comments) text += c + "\n";
  for (const auto& l : lines) text += l.second + "\n";
  WriteFileAtomic(index.name, std::vector<unsigned char>(text.begin(), text.end()));
}

void TumSequenceWriter::Close() {
  if (closed_) return;
  closed_ = true;
  Flush();
  for (IndexFile* index : {&rgb_index_, &depth_index_, &groundtruth_index_, &associations_index_,
                           &frames_index_}) {
    if (index->fd < 0) continue;
    ::close(index->fd);
    index->fd = -1;
    SortIndex(*index);
  }
}

}  // namespace p2i::slam_sink
