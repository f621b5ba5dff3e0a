/// @file recording_test_util.h
/// @brief Helpers of the recording tests: temp folders, sample p2i messages, writing file bytes
/// (reading them: p2i::testing::ReadFile, tests/read_file.h, not included here: its namespace
/// p2i::testing would make `testing::` ambiguous in files using namespace p2i::recording).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "convert/pose.h"
#include "msgs/codec.h"

namespace p2i::recording::testing {

inline std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("p2i_recording_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

/// A small RgbdFrame (w x h, pixel values derived from `seed`) with camera info and pose.
inline msgs::RgbdFrame SampleFrame(uint32_t w, uint32_t h, int seed) {
  msgs::RgbdFrame f;
  auto* hd = msgs::MutableHeader(f);
  hd->set_seq(static_cast<uint64_t>(seed) + 1);
  hd->set_capture_stamp_ns(1000000000ll * 1700000000 + seed * 33000000ll);
  hd->set_publish_stamp_ns(hd->capture_stamp_ns() + 1000);
  hd->set_frame_id("camera");
  hd->set_publisher("/test");
  auto* ci = f.meta.mutable_camera_info();
  ci->set_width(w);
  ci->set_height(h);
  for (double v : {50.0, 0.0, w / 2.0, 0.0, 50.0, h / 2.0, 0.0, 0.0, 1.0}) ci->add_k(v);
  convert::SetPose({0.1 * seed, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0}, f.meta.mutable_pose());
  f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, w, h);
  f.depth = msgs::Image::Allocate(msgs::pb::DEPTH32F, w, h);
  for (size_t i = 0; i < f.rgb.data->size(); ++i) f.rgb.MutableData()[i] = (i * 7 + seed) & 0xff;
  auto* d = reinterpret_cast<float*>(f.depth.MutableData());
  for (size_t i = 0; i < static_cast<size_t>(w) * h; ++i) d[i] = 0.5f + 0.001f * (i % 1000) + seed;
  return f;
}

inline void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), bytes.size());
}

}  // namespace p2i::recording::testing
