/// @file replay_buffer_test.cc
/// @brief ReplayBuffer: memory bound, recent + old policy, pose-less frames, persistence.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <set>

#include "nodes/trainer/replay_buffer.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;
using p2i::trainer::ReplayBuffer;

namespace {

const scene::CameraInfo kCamera = scene::CameraInfo::Pinhole(16, 12, 10.0, 10.0, 8.0, 6.0);

/// Frame i: 16x12, uniform colour i % 256, depth 1 + i mm, stamp i.
scene::RgbdSample Frame(int i) {
  scene::RgbdSample s;
  s.stamp = i;
  s.pose = scene::Pose(Eigen::Vector3d(0.01 * i, 0, 0), Eigen::Quaterniond::Identity());
  s.rgb = cv::Mat(12, 16, CV_8UC3, cv::Scalar(i % 256, (i * 7) % 256, 3));
  s.depth = cv::Mat(12, 16, CV_32FC1, cv::Scalar(1.0 + 0.001 * i));
  return s;
}

ReplayBuffer::Options Small(const std::string& dir, size_t capacity) {
  ReplayBuffer::Options o;
  o.dir = dir;
  o.width = o.height = 8;
  o.max_mb = (capacity * ReplayBuffer::BytesPerFrame(8, 8) + 1) / (1024.0 * 1024.0);
  o.recent_fraction = 0.5;
  return o;
}

std::vector<double> Stamps(const scene::RgbdDataset& d) {
  std::vector<double> s;
  for (const auto& f : d.frames) s.push_back(f.stamp);
  std::sort(s.begin(), s.end());
  return s;
}

}  // namespace

TEST_CASE("ReplayBuffer: the memory bound caps the frames, stored at training size", "[unit]") {
  ReplayBuffer buffer(Small("", 10));
  REQUIRE(buffer.Capacity() == 10);
  for (int i = 0; i < 50; ++i) buffer.Add(Frame(i), kCamera);
  CHECK(buffer.Size() == 10);
  CHECK(buffer.Accepted() == 50);
  const auto snap = buffer.Snapshot();
  REQUIRE(snap.frames.size() == 10);
  for (const auto& f : snap.frames) {
    CHECK(f.rgb.cols == 8);
    CHECK(f.rgb.rows == 8);
    CHECK(f.depth.cols == 8);
  }
  CHECK(snap.camera.image_width == 8);
  CHECK(snap.camera.image_height == 8);
  // A larger bound holds more.
  auto o = Small("", 10);
  o.max_mb *= 3;
  ReplayBuffer big(o);
  for (int i = 0; i < 50; ++i) big.Add(Frame(i), kCamera);
  CHECK(big.Size() == 30);
}

TEST_CASE("ReplayBuffer: keeps the newest frames and a sample of older ones", "[unit]") {
  ReplayBuffer buffer(Small("", 10));
  REQUIRE(buffer.RecentCapacity() == 5);
  for (int i = 0; i < 400; ++i) buffer.Add(Frame(i), kCamera);
  const auto stamps = Stamps(buffer.Snapshot());
  REQUIRE(stamps.size() == 10);
  for (int i = 395; i < 400; ++i)
    CHECK(std::count(stamps.begin(), stamps.end(), static_cast<double>(i)) == 1);
  // The reservoir holds frames from before the window, and not only the latest of them.
  const auto old = std::count_if(stamps.begin(), stamps.end(), [](double s) { return s < 395; });
  CHECK(old == 5);
  CHECK(stamps.front() < 300);
}

TEST_CASE("ReplayBuffer: frames without a pose are counted and dropped", "[unit]") {
  ReplayBuffer buffer(Small("", 10));
  CHECK(buffer.Add(Frame(0), kCamera));
  CHECK_FALSE(buffer.Add(Frame(1), kCamera, /*has_pose=*/false));
  CHECK(buffer.Size() == 1);
  CHECK(buffer.DroppedNoPose() == 1);
}

TEST_CASE("ReplayBuffer: a restart reloads every frame it held", "[unit]") {
  const std::string dir = trainer::testing::TempDir("buffer_restart");
  std::vector<double> before;
  cv::Mat rgb_before;
  {
    ReplayBuffer buffer(Small(dir, 10));
    CHECK(buffer.Reloaded() == 0);
    for (int i = 0; i < 37; ++i) buffer.Add(Frame(i), kCamera);  // past a compaction (2 C)
    before = Stamps(buffer.Snapshot());
    rgb_before = buffer.Snapshot().frames.back().rgb.clone();
  }
  {
    ReplayBuffer buffer(Small(dir, 10));
    CHECK(buffer.Reloaded() == 10);
    const auto snap = buffer.Snapshot();
    CHECK(Stamps(snap) == before);
    CHECK(cv::norm(snap.frames.back().rgb, rgb_before, cv::NORM_INF) == 0);
    CHECK(std::abs(snap.frames.back().depth.at<float>(0, 0) - (1.0 + 0.001 * 36)) < 1e-3);
    CHECK(snap.camera.image_width == 8);
    // It keeps accepting and persisting after the reload.
    for (int i = 37; i < 40; ++i) buffer.Add(Frame(i), kCamera);
    before = Stamps(buffer.Snapshot());
  }
  ReplayBuffer again(Small(dir, 10));
  CHECK(Stamps(again.Snapshot()) == before);
  CHECK(std::count(before.begin(), before.end(), 39.0) == 1);
  // Only one capture generation is left on disk.
  int generations = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    generations += e.path().filename().string().rfind("gen_", 0) == 0;
  CHECK(generations == 1);
  std::filesystem::remove_all(dir);
}
