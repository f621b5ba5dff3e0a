/// @file render_tool_test.cc
/// @brief `p2i render` as a process: the folder it writes opens as a multi-sequence dataset.
#include <cstdlib>
#include <filesystem>

#include <catch2/catch.hpp>

#include "scene/dataset_loader.h"
#include "scene/splits.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"

namespace p2i::scene {
namespace {

TEST_CASE("p2i render writes one capture per trajectory at 20 frames/s", "[integration]") {
  runtime::testing::ScopedRunDir tmp;
  const std::string out = tmp.Path() + "/render";
  const std::string cmd = p2i::testing::BinDir() +
                          "/p2i render builtin:small_office -t orbit -t arm_sweep "
                          "--out " + out + " --width 32 --height 24 --max-frames 5 > /dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
  const DatasetIndex data = OpenDataset(out);
  CHECK(data.Sequences() == std::vector<std::string>{"seq-01", "seq-02"});
  REQUIRE(data.size() == 10);
  CHECK(data.camera().image_width == 32);
  CHECK(data.camera().image_height == 24);
  CHECK(data.frames()[1].stamp - data.frames()[0].stamp == Approx(0.05));
  CHECK(data.frames()[5].stamp == Approx(0.0));
  const RgbdSample s = data.Load(3);
  CHECK(cv::countNonZero(s.depth > 0.0f) > 32 * 24 / 2);
  // The two sequences are different trajectories.
  CHECK(Pose::TranslationDistance(data.frames()[0].pose, data.frames()[5].pose) > 0.1);
  CHECK(MakeAdjacentTrajectorySplit(data, "seq-01", "seq-02").test.size() == 5);
  // A second run into the same folder refuses to overwrite without --overwrite.
  CHECK(std::system((cmd + " 2>/dev/null").c_str()) != 0);
}

}  // namespace
}  // namespace p2i::scene
