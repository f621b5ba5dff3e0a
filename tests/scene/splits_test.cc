/// @file splits_test.cc
/// @brief The paper's three split settings: counts, disjointness, determinism, file round trip.
#include <algorithm>
#include <fstream>
#include <set>

#include <catch2/catch.hpp>

#include "scene/splits.h"
#include "tests/scene/dataset_test_util.h"

namespace p2i::scene {
namespace {

/// A pose-only dataset: `counts[k]` frames in sequence "seq-0k+1", stamps at 20 Hz.
DatasetIndex FakeDataset(const std::vector<int>& counts) {
  std::vector<FrameRef> frames;
  for (size_t k = 0; k < counts.size(); ++k) {
    const std::string seq = "seq-0" + std::to_string(k + 1);
    for (int i = 0; i < counts[k]; ++i) {
      FrameRef f;
      f.sequence = seq;
      char id[64];
      std::snprintf(id, sizeof(id), "%s/%06d", seq.c_str(), i);
      f.id = id;
      f.stamp = i * 0.05;
      frames.push_back(f);
    }
  }
  return DatasetIndex(CameraInfo(), DepthEncoding(), frames);
}

TEST_CASE("MissingFramesMask follows the paper's (100m+1 ... 100m+N) rule", "[unit]") {
  const auto mask = MissingFramesMask(350, 3);
  std::vector<size_t> held;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (mask[i]) held.push_back(i);
  }
  CHECK(held == std::vector<size_t>{100, 101, 102, 200, 201, 202, 300, 301, 302});
  // The last block must be complete: 310 frames, N = 20 -> block at 300 would need 320.
  const auto partial = MissingFramesMask(310, 20);
  CHECK(std::count(partial.begin(), partial.end(), true) == 40);
  CHECK_FALSE(partial[300]);
  CHECK(partial[219]);
  CHECK_FALSE(partial[220]);
  // Nothing is held out of the first block.
  CHECK(std::count(mask.begin(), mask.begin() + 100, true) == 0);
  CHECK_THROWS_AS(MissingFramesMask(100, 0), std::invalid_argument);
  CHECK_THROWS_AS(MissingFramesMask(100, 100), std::invalid_argument);
}

TEST_CASE("Missing-frames split: counts per N, disjoint, deterministic", "[unit]") {
  const DatasetIndex data = FakeDataset({1000, 250});
  for (int n : {1, 3, 10, 20}) {
    const Split s = MakeMissingFramesSplit(data, n);
    // seq-01: blocks at 100..900 (9 of them); seq-02: blocks at 100, 200 (250 >= 200 + 20).
    CHECK(s.test.size() == static_cast<size_t>(11 * n));
    CHECK(s.train.size() + s.test.size() == 1250);
    std::set<std::string> train(s.train.begin(), s.train.end());
    for (const std::string& id : s.test) CHECK(train.count(id) == 0);
    CHECK(s == MakeMissingFramesSplit(data, n));
  }
  const Split one = MakeMissingFramesSplit(data, 3, 100, {"seq-02"});
  CHECK(one.train.size() + one.test.size() == 250);
  CHECK(one.test.front() == "seq-02/000100");
  // Small period for short sequences (the 50-frame real data).
  const Split small = MakeMissingFramesSplit(FakeDataset({50}), 2, 10);
  CHECK(small.test.size() == 8);
  CHECK(small.test.front() == "seq-01/000010");
}

TEST_CASE("Trajectory splits use whole sequences", "[unit]") {
  const DatasetIndex data = FakeDataset({30, 40, 50});
  const Split b = MakeAdjacentTrajectorySplit(data, "seq-01", "seq-02");
  CHECK(b.setting == SplitSetting::kAdjacentTrajectory);
  CHECK(b.train.size() == 30);
  CHECK(b.test.size() == 40);
  const Split c = MakeCrossTrajectorySplit(data, {"seq-01", "seq-03"}, {"seq-02"});
  CHECK(c.train.size() == 80);
  CHECK(c.test.size() == 40);
  CHECK(std::all_of(c.test.begin(), c.test.end(),
                    [](const std::string& id) { return id.rfind("seq-02/", 0) == 0; }));
  CHECK_THROWS_WITH(MakeAdjacentTrajectorySplit(data, "seq-01", "seq-01"),
                    Catch::Contains("both"));
  CHECK_THROWS_WITH(MakeCrossTrajectorySplit(data, {"seq-01"}, {"seq-09"}),
                    Catch::Contains("seq-09"));
  CHECK_THROWS_AS(MakeCrossTrajectorySplit(data, {"seq-01", "seq-02"}, {"seq-02"}),
                  std::invalid_argument);
}

TEST_CASE("Split file round trip and validation", "[unit]") {
  p2i::testing::TempDir tmp;
  const DatasetIndex data = FakeDataset({230, 60});
  for (const Split& s : {MakeMissingFramesSplit(data, 10),
                         MakeAdjacentTrajectorySplit(data, "seq-02", "seq-01"),
                         MakeCrossTrajectorySplit(data, {"seq-01"}, {"seq-02"})}) {
    const std::string path = tmp / (ToString(s.setting) + ".yaml");
    s.ToYamlFile(path);
    const Split back = Split::FromYamlFile(path);
    CHECK(back == s);
    CHECK(back.setting == s.setting);
  }
  const std::string text = MakeMissingFramesSplit(data, 3).ToYamlString();
  CHECK_THROWS_WITH(Split::FromYamlString(text + "hold_out: 4\n", "f.yaml"),
                    Catch::Contains("hold_out") && Catch::Contains("f.yaml"));
  // A test id also in train is rejected.
  Split bad = MakeMissingFramesSplit(data, 3);
  bad.test.push_back(bad.train.front());
  CHECK_THROWS_WITH(Split::FromYamlString(bad.ToYamlString(), "g.yaml"),
                    Catch::Contains("twice"));
  CHECK_THROWS_WITH(SplitSettingFromString("random"), Catch::Contains("missing_frames"));
}

TEST_CASE("Evaluation settings a1..c parse once, print back and sort in the paper's order",
          "[unit]") {
  std::vector<std::string> names;
  for (const EvalSetting& s : PaperSettings()) {
    names.push_back(s.Name());
    CHECK(EvalSetting::Parse(s.Name()) == s);
  }
  CHECK(names == std::vector<std::string>{"a1", "a3", "a10", "a20", "b", "c"});
  const EvalSetting a10 = EvalSetting::Parse("a10");
  CHECK(a10.split == SplitSetting::kMissingFrames);
  CHECK(a10.held_out == 10);
  CHECK(EvalSetting::Parse("b").split == SplitSetting::kAdjacentTrajectory);
  CHECK(EvalSetting::Parse("c").held_out == 0);
  std::vector<EvalSetting> mixed = {EvalSetting::Parse("c"), EvalSetting::Parse("a20"),
                                    EvalSetting::Parse("b"), EvalSetting::Parse("a3")};
  std::sort(mixed.begin(), mixed.end());  // a3 < a20 by N, not as text
  CHECK(mixed[0].Name() == "a3");
  CHECK(mixed[1].Name() == "a20");
  CHECK(mixed[3].Name() == "c");
  CHECK_THROWS_WITH(EvalSetting::Parse("a5"), Catch::Contains("'a5'") && Catch::Contains("a20"));
  CHECK_THROWS_AS(EvalSetting::Parse("d"), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::scene
