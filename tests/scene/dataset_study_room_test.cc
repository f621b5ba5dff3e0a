/// @file dataset_study_room_test.cc
/// @brief The loaders on real data: ../shared/data/study-room (skipped when absent).
#include <cmath>
#include <filesystem>

#include <catch2/catch.hpp>

#include "scene/dataset_loader.h"
#include "scene/image_ops.h"
#include "scene/seven_scenes.h"
#include "scene/splits.h"
#include "tests/skip.h"
#include "tests/test_paths.h"

namespace p2i::scene {
namespace {

std::string StudyRoom() { return p2i::testing::SharedDir() + "/data/study-room"; }

bool Available() { return std::filesystem::is_directory(StudyRoom()); }
// Skips the test case (ctest: skipped) when the data is absent.
#define SKIP_WITHOUT_DATA()                                                                 \
  if (!Available())                                                                         \
  P2I_SKIP("real data not found at " << StudyRoom() << " (set P2I_SHARED_DIR to the shared " \
                                                       "folder)")

DatasetIndex Open() {
  SevenScenesOptions o;
  o.depth.invalid_value = 0;  // the README: 0 = no depth in this data
  return ReadSevenScenes(StudyRoom(), o);
}

TEST_CASE("Study-room data: 2 x 50 frames with finite unit poses", "[unit]") {
  SKIP_WITHOUT_DATA();
  const DatasetIndex index = Open();
  REQUIRE(index.Sequences() == std::vector<std::string>{"seq-01", "seq-02"});
  CHECK(index.SelectSequences({"seq-01"}).size() == 50);
  CHECK(index.SelectSequences({"seq-02"}).size() == 50);
  CHECK(index.frames().front().id == "seq-01/frame-000935");
  CHECK(index.frames().back().id == "seq-02/frame-003209");
  CHECK(index.camera().fx() == Approx(570.342205));
  CHECK(index.camera().cx() == Approx(320.0));
  CHECK(index.camera().image_width == 640);
  for (const FrameRef& f : index.frames()) {
    CHECK(f.pose.ToVector7().allFinite());
    CHECK(f.pose.rotation().norm() == Approx(1.0).margin(1e-9));
  }
  // Consecutive frames 11-15 mm apart (the README), i.e. a real trajectory, not a shuffle.
  double max_step = 0.0;
  for (size_t i = 1; i < 50; ++i) {
    max_step = std::max(max_step, Pose::TranslationDistance(index.frames()[i - 1].pose,
                                                            index.frames()[i].pose));
  }
  CHECK(max_step < 0.05);
  CHECK(DetectDatasetFormat(StudyRoom()) == "7scenes");
}

TEST_CASE("Study-room data: the two trajectories' centres are about 2.8 m apart", "[unit]") {
  SKIP_WITHOUT_DATA();
  const DatasetIndex index = Open();
  Eigen::Vector3d centre[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (const FrameRef& f : index.frames()) {
    centre[f.sequence == "seq-01" ? 0 : 1] += f.pose.translation() / 50.0;
  }
  const double distance = (centre[0] - centre[1]).norm();
  INFO("centre distance " << distance << " m");
  CHECK(distance == Approx(2.8).margin(0.3));
}

TEST_CASE("Study-room data: pixels, depth validity and a training-size crop", "[unit]") {
  SKIP_WITHOUT_DATA();
  const DatasetIndex index = Open();
  double invalid = 0.0;
  const size_t picks[] = {0, 25, 49, 50, 99};
  for (size_t i : picks) {
    const RgbdSample s = index.Load(i);
    REQUIRE(s.rgb.type() == CV_8UC3);
    REQUIRE(s.depth.type() == CV_32FC1);
    invalid += cv::countNonZero(s.depth == 0.0f) / static_cast<double>(s.depth.total());
    double lo, hi;
    cv::minMaxLoc(s.depth, &lo, &hi, nullptr, nullptr, s.depth > 0.0f);
    CHECK(lo > 0.1);   // metres, not millimetres
    CHECK(hi < 15.0);
  }
  invalid /= 5.0;
  INFO("mean invalid depth ratio " << invalid);
  CHECK(invalid == Approx(0.12).margin(0.03));

  const RgbdSample small = CenterCropResizeSample(index.Load(0), 128, 128);
  CHECK(small.rgb.size() == cv::Size(128, 128));
  CHECK(small.depth.size() == cv::Size(128, 128));

  // The adjacent-trajectory split of this data.
  const Split b = MakeAdjacentTrajectorySplit(index, "seq-01", "seq-02");
  CHECK(b.train.size() == 50);
  CHECK(b.test.size() == 50);
}

}  // namespace
}  // namespace p2i::scene
