/// @file densify_test.cc
/// @brief Geometry-densified training frames (model/densify.h): nearby poses stay within their
/// bounds, the added views are the named method's renders at those poses, deterministic, and bad
/// settings are errors that name them.
#include "model/densify.h"

#include <set>
#include <stdexcept>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>

#include "model/baseline_warp.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::model {
namespace {

scene::RgbdDataset SmallOffice(int step) {
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  scene::RgbdDataset data;
  data.camera = scene::SimScene::DefaultCamera(32, 32);
  const auto sweep = scene::GenerateArmSweep({});
  for (size_t i = 0; i < sweep.size(); i += static_cast<size_t>(step)) {
    scene::RgbdSample f = sim.Render(sweep[i].pose, data.camera);
    f.id = "seq-01/" + std::to_string(i);
    data.frames.push_back(std::move(f));
  }
  return data;
}

P2iConfig DensifyWarp(double ratio, double offset_m, double angle_deg) {
  P2iConfig c;
  c.densify_ratio = ratio;
  c.densify_offset_m = offset_m;
  c.densify_angle_deg = angle_deg;
  c.densify_method = "warp";
  return c;
}

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST_CASE("NearbyPose moves and turns a pose within its bounds, and uses them", "[unit]") {
  std::mt19937_64 rng(7);
  const scene::Pose base(Eigen::Vector3d(1.0, 2.0, 0.5),
                         Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())));
  double max_t = 0.0, max_r = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < 2000; ++i) {
    const scene::Pose p = NearbyPose(base, 0.2, 12.0, rng);
    const double t = scene::Pose::TranslationDistance(p, base);
    const double r = scene::Pose::RotationDistanceDeg(p, base);
    REQUIRE(t <= 0.2 + 1e-9);
    REQUIRE(r <= 12.0 + 1e-6);
    max_t = std::max(max_t, t);
    max_r = std::max(max_r, r);
    mean += p.translation() - base.translation();
  }
  CHECK(max_t > 0.19);  // the bound is reached, not a fraction of it
  CHECK(max_r > 11.5);
  CHECK((mean / 2000.0).norm() < 0.02);  // no preferred direction
  std::mt19937_64 still(1);
  const scene::Pose same = NearbyPose(base, 0.0, 0.0, still);
  CHECK(scene::Pose::TranslationDistance(same, base) < 1e-12);
  CHECK(scene::Pose::RotationDistanceDeg(same, base) < 1e-6);
}

TEST_CASE("DensifyTrainingFrames appends the method's own renders at nearby poses", "[unit]") {
  const scene::RgbdDataset train = SmallOffice(40);
  REQUIRE(train.frames.size() >= 8);
  const P2iConfig c = DensifyWarp(1.5, 0.1, 5.0);
  DensifyReport report;
  const scene::RgbdDataset out = DensifyTrainingFrames(train, c, &report);
  const size_t n = train.frames.size();
  const int expected = static_cast<int>(std::lround(1.5 * static_cast<double>(n)));
  REQUIRE(report.added == expected);
  REQUIRE(out.frames.size() == n + static_cast<size_t>(expected));
  for (size_t i = 0; i < n; ++i) {
    CHECK(out.frames[i].id == train.frames[i].id);
    CHECK_FALSE(IsDensified(out.frames[i]));
    CHECK(SameImage(out.frames[i].rgb, train.frames[i].rgb));
  }
  // Each added view is warp's render at its pose, and that pose lies within the bounds of some
  // training pose without being one of them.
  DepthWarpOptions wo;
  wo.fill_holes = true;  // the registry's warp fills holes
  DepthWarp warp(train, wo);
  std::set<std::string> ids;
  for (size_t i = n; i < out.frames.size(); ++i) {
    const scene::RgbdSample& v = out.frames[i];
    CHECK(v.id.rfind("densify/", 0) == 0);
    CHECK(IsDensified(v));
    ids.insert(v.id);
    const scene::RgbdSample ref = warp.Render(v.pose);
    CHECK(SameImage(v.rgb, ref.rgb));
    CHECK(SameImage(v.depth, ref.depth));
    double nearest_t = 1e9, nearest_r = 1e9;
    for (const auto& f : train.frames) {
      const double t = scene::Pose::TranslationDistance(v.pose, f.pose);
      if (t < nearest_t) nearest_t = t, nearest_r = scene::Pose::RotationDistanceDeg(v.pose, f.pose);
    }
    CHECK(nearest_t <= 0.1 + 1e-9);
    CHECK(nearest_r <= 30.0);  // the nearest in translation is close in angle too on a sweep
  }
  CHECK(ids.size() == static_cast<size_t>(expected));
  // Not the training frames re-served: views off the path differ from their nearest frame.
  int differing = 0;
  for (size_t i = n; i < out.frames.size(); ++i) {
    bool equals_some = false;
    for (const auto& f : train.frames) equals_some = equals_some || SameImage(out.frames[i].rgb, f.rgb);
    differing += equals_some ? 0 : 1;
  }
  CHECK(differing == expected);
}

TEST_CASE("DensifyTrainingFrames is deterministic for one seed and varies with it", "[unit]") {
  const scene::RgbdDataset train = SmallOffice(60);
  P2iConfig c = DensifyWarp(1.0, 0.15, 10.0);
  const scene::RgbdDataset a = DensifyTrainingFrames(train, c);
  const scene::RgbdDataset b = DensifyTrainingFrames(train, c);
  REQUIRE(a.frames.size() == b.frames.size());
  for (size_t i = train.frames.size(); i < a.frames.size(); ++i) {
    CHECK(scene::Pose::TranslationDistance(a.frames[i].pose, b.frames[i].pose) == 0.0);
    CHECK(SameImage(a.frames[i].rgb, b.frames[i].rgb));
  }
  c.seed = 2;
  const scene::RgbdDataset other = DensifyTrainingFrames(train, c);
  CHECK(scene::Pose::TranslationDistance(other.frames.back().pose, a.frames.back().pose) > 1e-6);
}

TEST_CASE("DensifyTrainingFrames: off adds nothing, bad methods and sizes are errors", "[unit]") {
  const scene::RgbdDataset train = SmallOffice(60);
  P2iConfig off;
  DensifyReport report;
  CHECK(DensifyTrainingFrames(train, off, &report).frames.size() == train.frames.size());
  CHECK(report.added == 0);
  P2iConfig learned = DensifyWarp(1.0, 0.1, 5.0);
  learned.densify_method = "p2i";
  CHECK_THROWS_WITH(DensifyTrainingFrames(train, learned),
                    Catch::Contains("densify_method 'p2i' is learned"));
  P2iConfig unknown = DensifyWarp(1.0, 0.1, 5.0);
  unknown.densify_method = "magic";
  CHECK_THROWS_WITH(DensifyTrainingFrames(train, unknown), Catch::Contains("densify_method: method 'magic' is not one of"));
}

TEST_CASE("NearAnyFrame needs both the distance and the angle within the gap", "[unit]") {
  const scene::RgbdDataset train = SmallOffice(60);
  const scene::Pose at = train.frames[1].pose;
  CHECK(NearAnyFrame(at, train.frames, 0.04, 5.0));
  const scene::Pose moved(at.translation() + Eigen::Vector3d(0.0, 0.0, 0.05), at.rotation());
  CHECK_FALSE(NearAnyFrame(moved, train.frames, 0.04, 5.0));
  CHECK(NearAnyFrame(moved, train.frames, 0.06, 5.0));
  const scene::Pose turned(at.translation(),
                           at.rotation() * Eigen::Quaterniond(Eigen::AngleAxisd(10.0 * M_PI / 180.0,
                                                                                 Eigen::Vector3d::UnitX())));
  CHECK_FALSE(NearAnyFrame(turned, train.frames, 0.04, 5.0));
  CHECK(NearAnyFrame(turned, train.frames, 0.04, 11.0));
}

TEST_CASE("DensifyTrainingFrames with a min gap drops poses near training frames, more in a denser capture",
          "[unit]") {
  P2iConfig c = DensifyWarp(1.0, 0.1, 5.0);
  c.densify_min_gap_m = 0.04;
  c.densify_min_gap_deg = 5.0;
  double skipped_share[2] = {0.0, 0.0};
  const int steps[2] = {40, 4};  // a sparse and a ten times denser capture of the same sweep
  for (int k = 0; k < 2; ++k) {
    const scene::RgbdDataset train = SmallOffice(steps[k]);
    DensifyReport report;
    const scene::RgbdDataset out = DensifyTrainingFrames(train, c, &report);
    REQUIRE(out.frames.size() == train.frames.size() + static_cast<size_t>(report.added));
    REQUIRE(report.added > 0);
    for (size_t i = train.frames.size(); i < out.frames.size(); ++i) {
      INFO(out.frames[i].id);
      CHECK_FALSE(NearAnyFrame(out.frames[i].pose, train.frames, 0.04, 5.0));
    }
    skipped_share[k] = report.skipped / static_cast<double>(report.added + report.skipped);
    CHECK(DensifySummary(report, c).find(std::to_string(report.skipped) + " candidates skipped") !=
          std::string::npos);
  }
  CHECK(skipped_share[1] > skipped_share[0] + 0.2);
  // The kept views are the gap-off run's views minus the dropped ones, in order.
  const scene::RgbdDataset train = SmallOffice(4);
  const scene::RgbdDataset with_gap = DensifyTrainingFrames(train, c);
  c.densify_min_gap_m = 0.0;
  DensifyReport off;
  const scene::RgbdDataset without = DensifyTrainingFrames(train, c, &off);
  CHECK(off.skipped == 0);
  CHECK(off.added == static_cast<int>(train.frames.size()));
  size_t j = train.frames.size();
  for (size_t i = train.frames.size(); i < with_gap.frames.size(); ++i) {
    while (j < without.frames.size() &&
           scene::Pose::TranslationDistance(without.frames[j].pose, with_gap.frames[i].pose) > 0.0)
      ++j;
    REQUIRE(j < without.frames.size());
    CHECK(SameImage(without.frames[j].rgb, with_gap.frames[i].rgb));
    ++j;
  }
  // A gap nothing escapes: every candidate dropped.
  c.densify_min_gap_m = 10.0;
  c.densify_min_gap_deg = 180.0;
  DensifyReport none;
  CHECK(DensifyTrainingFrames(train, c, &none).frames.size() == train.frames.size());
  CHECK(none.added == 0);
  CHECK(none.skipped == static_cast<int>(train.frames.size()));
  c.densify_min_gap_m = 0.0;
  CHECK(DensifySummary(off, c).find("skipped") == std::string::npos);
  CHECK(DensifySummary(off, c).find("densified: " + std::to_string(off.added) + " views of warp") == 0);
}

TEST_CASE("densify keys: read from YAML, written back, bad values name the key", "[unit]") {
  const P2iConfig c = P2iConfig::FromYamlString(
      "densify_ratio: 2\ndensify_offset_m: 0.2\ndensify_angle_deg: 15\ndensify_method: warp\n", "t");
  CHECK(c.densify_ratio == 2.0);
  CHECK(c.densify_offset_m == 0.2);
  CHECK(c.densify_angle_deg == 15.0);
  CHECK(c.densify_method == "warp");
  const P2iConfig back = P2iConfig::FromYamlString(c.ToYamlString(), "round trip");
  CHECK(back.densify_ratio == 2.0);
  CHECK(back.densify_method == "warp");
  CHECK(P2iConfig{}.densify_ratio == 0.0);  // off unless a config asks
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("densify_ratio: -1\n", "t"),
                    Catch::Contains("densify_ratio"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("densify_angle_deg: 120\n", "t"),
                    Catch::Contains("densify_angle_deg"));
  const P2iConfig g = P2iConfig::FromYamlString("densify_min_gap_m: 0.05\ndensify_min_gap_deg: 3\n", "t");
  const P2iConfig g_back = P2iConfig::FromYamlString(g.ToYamlString(), "round trip");
  CHECK(g_back.densify_min_gap_m == 0.05);
  CHECK(g_back.densify_min_gap_deg == 3.0);
  CHECK(P2iConfig{}.densify_min_gap_m == 0.0);  // off unless a config asks
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("densify_min_gap_m: -0.1\n", "t"),
                    Catch::Contains("densify_min_gap_m"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("densify_min_gap_deg: 200\n", "t"),
                    Catch::Contains("densify_min_gap_deg"));
  CHECK(P2iConfig{}.densify_real_share == 0.0);  // off unless a config asks
  CHECK(P2iConfig::FromYamlString(P2iConfig::FromYamlString("densify_real_share: 0.5\n", "t").ToYamlString(),
                                  "round trip")
            .densify_real_share == 0.5);
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("densify_real_share: 1\n", "t"),
                    Catch::Contains("densify_real_share must be in [0, 1)"));
  CHECK(P2iConfig{}.densify_steps == -1);  // densified views in every step unless a config asks
  CHECK(P2iConfig::FromYamlString(P2iConfig::FromYamlString("densify_steps: 5000\n", "t").ToYamlString(),
                                  "t")
            .densify_steps == 5000);
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("densify_steps: -2\n", "t"),
                    Catch::Contains("densify_steps must be >= -1"));
}

}  // namespace
}  // namespace p2i::model
