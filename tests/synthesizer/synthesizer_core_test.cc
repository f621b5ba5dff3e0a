/// @file synthesizer_core_test.cc
/// @brief SynthesizerCore and TopicRenderer with a fake ViewSynthesizer: batch replies, model
/// version per view, coverage, bad requests, hot swap under load, latest-only skipping.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/synthesizer/latest_slot.h"
#include "nodes/synthesizer/synthesizer_core.h"
#include "nodes/synthesizer/topic_renderer.h"
#include "scene/trajectory_io.h"

namespace p2i::nodes {
namespace {

constexpr int kW = 8, kH = 6;

/// Renders a constant image: red channel = its model version (mod 256), depth = pose x + 1, so
/// a test can tell which model rendered a view and for which pose.
class FakeSynthesizer : public model::ViewSynthesizer {
 public:
  FakeSynthesizer(uint64_t version, std::chrono::milliseconds render_time, bool fail = false)
      : version_(version), render_time_(render_time), fail_(fail) {}
  std::string Name() const override { return "fake"; }
  scene::CameraInfo Camera() const override {
    return scene::CameraInfo::Pinhole(kW, kH, 5, 5, 3.5, 2.5);
  }
  scene::RgbdSample Render(const scene::Pose& pose) override {
    if (fail_) throw std::runtime_error("fake render failure");
    if (render_time_.count() > 0) std::this_thread::sleep_for(render_time_);
    scene::RgbdSample v;
    v.pose = pose;
    v.rgb = cv::Mat(kH, kW, CV_8UC3, cv::Scalar(static_cast<double>(version_ % 256), 10, 20));
    v.depth = cv::Mat(kH, kW, CV_32FC1, cv::Scalar(pose.translation().x() + 1.0));
    return v;
  }

 private:
  uint64_t version_;
  std::chrono::milliseconds render_time_;
  bool fail_;
};

/// A FakeSynthesizer with scene geometry: the view at x was observed on 1 / (1 + x) of its pixels
/// and seen 10 x degrees off its keyframes.
class FakeGeometrySynthesizer : public FakeSynthesizer {
 public:
  using FakeSynthesizer::FakeSynthesizer;
  std::vector<scene::RgbdSample> RenderBatch(const std::vector<scene::Pose>& poses) override {
    geometry_.clear();
    std::vector<scene::RgbdSample> out;
    for (const auto& p : poses) {
      out.push_back(Render(p));
      const double x = p.translation().x();
      geometry_.push_back({1.0 / (1.0 + x), 10.0 * x});
    }
    return out;
  }
  std::vector<model::ViewGeometry> LastGeometry() const override { return geometry_; }

 private:
  std::vector<model::ViewGeometry> geometry_;
};

SynthesizerLoader FakeLoader(std::chrono::milliseconds render_time = {},
                             std::chrono::milliseconds load_time = {},
                             std::atomic<bool>* loading = nullptr) {
  return [=](const ModelSpec& spec) -> std::unique_ptr<model::ViewSynthesizer> {
    if (loading) *loading = true;
    if (load_time.count() > 0) std::this_thread::sleep_for(load_time);
    if (spec.checkpoint_path == "broken") {
      if (loading) *loading = false;
      throw std::runtime_error("cannot read checkpoint 'broken'");
    }
    auto s = std::make_unique<FakeSynthesizer>(spec.version, render_time,
                                               spec.checkpoint_path == "fails_to_render");
    if (loading) *loading = false;
    return s;
  };
}

msgs::pb::Pose PoseAtX(double x) {
  msgs::pb::Pose p;
  convert::ToMsg(scene::Pose(Eigen::Vector3d(x, 0.0, 1.0), Eigen::Quaterniond::Identity()), &p);
  return p;
}

/// Training poses x = 0, 0.1, ..., 0.9 for the coverage score.
std::shared_ptr<const model::CoverageScorer> LineCoverage() {
  std::vector<scene::Pose> poses;
  for (int i = 0; i < 10; ++i) {
    poses.emplace_back(Eigen::Vector3d(0.1 * i, 0.0, 1.0), Eigen::Quaterniond::Identity());
  }
  return std::make_shared<const model::CoverageScorer>(poses);
}

msgs::pb::RenderRequest Request(std::vector<double> xs, uint64_t id = 1) {
  msgs::pb::RenderRequest r;
  r.set_request_id(id);
  for (double x : xs) *r.add_poses() = PoseAtX(x);
  return r;
}

uint8_t Red(const msgs::Image& img) { return convert::ToMat(img).at<cv::Vec3b>(0, 0)[0]; }
float Depth(const msgs::Image& img) { return convert::ToMat(img).at<float>(0, 0); }

/// Checks a reply is ok and that all its views were rendered by one model; returns its version.
uint64_t CheckOneModel(const msgs::RenderReplyMsg& reply) {
  REQUIRE(reply.meta.ok());
  REQUIRE(reply.meta.views_size() > 0);
  REQUIRE(reply.images.size() == 2u * reply.meta.views_size());
  const uint64_t v = reply.meta.views(0).model_version();
  for (int i = 0; i < reply.meta.views_size(); ++i) {
    REQUIRE(reply.meta.views(i).model_version() == v);
    REQUIRE(Red(reply.images[2 * i]) == v % 256);  // the reported model is the one that rendered
  }
  return v;
}

TEST_CASE("SynthesizerCore answers a batch with one view per pose, in order, with metadata",
          "[unit]") {
  SynthesizerCoreOptions options;
  options.method = "nearest";
  options.max_batch = 2;  // 5 poses -> 3 batches
  SynthesizerCore core(options, FakeLoader(), LineCoverage());
  core.LoadNow({7, "", "nearest"});
  REQUIRE(core.CurrentVersion() == 7);

  msgs::RenderReplyMsg reply;
  const std::vector<double> xs{0.0, 0.3, 0.45, 2.0, 5.0};
  core.HandleRender(Request(xs, 42), SynthesizerCore::Clock::now(), &reply);
  REQUIRE(reply.meta.ok());
  CHECK(reply.meta.error().empty());
  CHECK(reply.meta.request_id() == 42);
  REQUIRE(reply.meta.views_size() == 5);
  REQUIRE(reply.images.size() == 10);
  for (int i = 0; i < 5; ++i) {
    const auto& v = reply.meta.views(i);
    CHECK(v.model_version() == 7);
    CHECK(v.method() == "nearest");
    CHECK(v.pose().position().x() == Approx(xs[i]));
    CHECK(v.queue_ms() >= 0.0);
    CHECK(v.render_ms() >= 0.0);
    CHECK(reply.images[2 * i].encoding == msgs::pb::RGB8);
    CHECK(reply.images[2 * i].width == static_cast<uint32_t>(kW));
    CHECK(reply.images[2 * i + 1].encoding == msgs::pb::DEPTH32F);
    CHECK(Red(reply.images[2 * i]) == 7);
    CHECK(Depth(reply.images[2 * i + 1]) == Approx(xs[i] + 1.0));  // view i is pose i
  }
  // Coverage: 1 on a training pose, decreasing away from the training line.
  CHECK(reply.meta.views(0).coverage() == Approx(1.0));
  CHECK(reply.meta.views(1).coverage() == Approx(1.0));
  CHECK(reply.meta.views(2).coverage() < 1.0);
  CHECK(reply.meta.views(2).coverage() > reply.meta.views(3).coverage());
  CHECK(reply.meta.views(4).coverage() < 0.01);
  // Later batches wait for earlier ones: queue time does not decrease along the request.
  CHECK(reply.meta.views(4).queue_ms() >= reply.meta.views(0).queue_ms());
  CHECK(core.Counter("views") == 5);
  CHECK(core.Counter("requests") == 1);

  // RenderView (topic mode) fills the same metadata.
  msgs::View view;
  std::string error;
  REQUIRE(core.RenderView(PoseAtX(0.2), SynthesizerCore::Clock::now(), &view, &error));
  CHECK(view.meta.model_version() == 7);
  CHECK(view.meta.coverage() == Approx(1.0));
  CHECK(view.meta.method() == "nearest");
  CHECK(Depth(view.depth) == Approx(1.2));
}

TEST_CASE("SynthesizerCore passes each view's geometry (observed fraction, keyframe angle) on, per view", "[unit]") {
  SynthesizerCoreOptions options;
  options.method = "fusion";
  options.max_batch = 2;  // 3 poses -> 2 batches: the geometry must follow each batch
  SynthesizerCore core(options, [](const ModelSpec& spec) -> std::unique_ptr<model::ViewSynthesizer> {
    return std::make_unique<FakeGeometrySynthesizer>(spec.version, std::chrono::milliseconds(0));
  }, LineCoverage());
  core.LoadNow({3, "", "fusion"});
  msgs::RenderReplyMsg reply;
  const std::vector<double> xs{0.0, 1.0, 3.0};
  core.HandleRender(Request(xs), SynthesizerCore::Clock::now(), &reply);
  REQUIRE(reply.meta.ok());
  REQUIRE(reply.meta.views_size() == 3);
  for (int i = 0; i < 3; ++i) {
    const auto& v = reply.meta.views(i);
    REQUIRE(v.has_observed_fraction());
    REQUIRE(v.has_keyframe_angle_deg());
    CHECK(v.observed_fraction() == Approx(1.0 / (1.0 + xs[i])));
    CHECK(v.keyframe_angle_deg() == Approx(10.0 * xs[i]));
  }
  msgs::View view;
  std::string error;
  REQUIRE(core.RenderView(PoseAtX(1.0), SynthesizerCore::Clock::now(), &view, &error));
  REQUIRE(view.meta.has_observed_fraction());
  CHECK(view.meta.observed_fraction() == Approx(0.5));
  CHECK(view.meta.keyframe_angle_deg() == Approx(10.0));

  // A method without geometry leaves the fields absent (not 0, which would read "nothing seen").
  SynthesizerCore plain(options, FakeLoader(), LineCoverage());
  plain.LoadNow({1, "", "nearest"});
  msgs::RenderReplyMsg r2;
  plain.HandleRender(Request({0.0}), SynthesizerCore::Clock::now(), &r2);
  REQUIRE(r2.meta.ok());
  CHECK_FALSE(r2.meta.views(0).has_observed_fraction());
  CHECK_FALSE(r2.meta.views(0).has_keyframe_angle_deg());
}

TEST_CASE("SynthesizerCore refuses bad requests with ok=false, counts them and keeps serving",
          "[unit]") {
  SynthesizerCoreOptions options;
  options.method = "p2i";
  options.max_poses = 4;
  SynthesizerCore core(options, FakeLoader(), nullptr);

  msgs::RenderReplyMsg reply;
  const auto now = SynthesizerCore::Clock::now;
  // Before any model: a clear error, not a crash.
  core.HandleRender(Request({0.0}), now(), &reply);
  CHECK_FALSE(reply.meta.ok());
  CHECK(reply.meta.error().find("no model") != std::string::npos);
  CHECK(core.Counter("no_model") == 1);

  core.LoadNow({1, "ckpt", "p2i"});
  auto refused = [&](const msgs::pb::RenderRequest& r, const std::string& what) {
    core.HandleRender(r, now(), &reply);
    INFO(what << ": " << reply.meta.error());
    CHECK_FALSE(reply.meta.ok());
    CHECK_FALSE(reply.meta.error().empty());
    CHECK(reply.meta.views_size() == 0);
    CHECK(reply.images.empty());
  };
  refused(Request({}), "no poses");
  refused(Request({0, 0.1, 0.2, 0.3, 0.4}), "too many poses");
  auto nan = Request({0.0, 0.1});
  nan.mutable_poses(1)->mutable_position()->set_y(std::numeric_limits<double>::quiet_NaN());
  refused(nan, "non-finite position");
  CHECK(reply.meta.error().find("poses[1].position is not finite") != std::string::npos);
  auto zero_q = Request({0.0});
  zero_q.mutable_poses(0)->mutable_orientation()->set_w(0.0);
  refused(zero_q, "zero quaternion");
  CHECK(reply.meta.error().find("poses[0].orientation has norm") != std::string::npos);
  auto other_method = Request({0.0});
  other_method.set_method("warp");
  refused(other_method, "another method");
  CHECK(core.Counter("bad_requests") == 5);
  auto late = Request({0.0});
  late.set_deadline_ns(1);  // 1 ns after the epoch: long past
  refused(late, "deadline");
  CHECK(core.Counter("expired") == 1);

  // A model whose render throws: the request fails cleanly.
  SynthesizerCore failing(options, FakeLoader(), nullptr);
  failing.LoadNow({1, "fails_to_render", "p2i"});
  failing.HandleRender(Request({0.0}), now(), &reply);
  CHECK_FALSE(reply.meta.ok());
  CHECK(reply.meta.error().find("fake render failure") != std::string::npos);
  CHECK(failing.Counter("render_errors") == 1);

  // And the first core still serves good requests.
  auto same_method = Request({0.0, 0.1});
  same_method.set_method("p2i");
  core.HandleRender(same_method, now(), &reply);
  CHECK(CheckOneModel(reply) == 1);
  CHECK(core.Counter("views") == 2);
}

TEST_CASE("Hot swap under continuous load: no failed request, no request mixes two models",
          "[unit]") {
  SynthesizerCoreOptions options;
  options.method = "p2i";
  options.max_batch = 1;  // one RenderBatch per pose: a swap mid-request would show as mixing
  std::atomic<bool> loading{false};
  SynthesizerCore core(options,
                       FakeLoader(std::chrono::milliseconds(1), std::chrono::milliseconds(60),
                                  &loading),
                       LineCoverage());
  core.LoadNow({1, "v1", "p2i"});

  constexpr int kClients = 3;
  constexpr uint64_t kLast = 6;
  std::atomic<bool> stop{false};
  std::atomic<int> failures{0}, replies{0}, replies_while_loading{0};
  std::vector<std::vector<uint64_t>> seen(kClients);
  std::vector<std::thread> clients;
  for (int c = 0; c < kClients; ++c) {
    clients.emplace_back([&, c] {
      uint64_t id = 0;
      while (!stop) {
        msgs::RenderReplyMsg reply;
        core.HandleRender(Request({0.0, 0.1, 0.2, 0.3}, ++id), SynthesizerCore::Clock::now(),
                          &reply);
        if (!reply.meta.ok() || reply.meta.views_size() != 4) {
          ++failures;
          continue;
        }
        const uint64_t v = reply.meta.views(0).model_version();
        bool one_model = true;
        for (int i = 0; i < 4; ++i) {
          one_model = one_model && reply.meta.views(i).model_version() == v &&
                      Red(reply.images[2 * i]) == v;
        }
        if (!one_model) ++failures;
        seen[c].push_back(v);
        ++replies;
        if (loading) ++replies_while_loading;
      }
    });
  }
  for (uint64_t v = 2; v <= kLast; ++v) {
    REQUIRE(core.SwapAsync({v, "v" + std::to_string(v), "p2i"}));
    REQUIRE(core.WaitForVersion(v, std::chrono::seconds(10)));
    // Let some requests run on this version before the next swap.
    const int before = replies;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (replies < before + 3 * kClients && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  stop = true;
  for (auto& t : clients) t.join();

  CHECK(failures == 0);
  CHECK(core.CurrentVersion() == kLast);
  CHECK(core.Counter("swaps") == kLast - 1);
  // Serving went on while models loaded in the background.
  CHECK(replies_while_loading > 0);
  std::set<uint64_t> versions;
  for (const auto& s : seen) {
    for (size_t i = 1; i < s.size(); ++i) CHECK(s[i] >= s[i - 1]);  // never back to an old one
    versions.insert(s.begin(), s.end());
  }
  CHECK(versions.count(1) == 1);
  CHECK(versions.count(kLast) == 1);
  CHECK(versions.size() >= 4);

  // Re-announced or older versions are ignored.
  CHECK_FALSE(core.SwapAsync({kLast, "again", "p2i"}));
  CHECK_FALSE(core.SwapAsync({2, "old", "p2i"}));
  CHECK(core.Counter("stale_versions") == 2);
}

TEST_CASE("A hot swap whose load fails keeps the old model serving", "[unit]") {
  SynthesizerCore core({}, FakeLoader(), nullptr);
  core.LoadNow({1, "v1", "p2i"});
  REQUIRE(core.SwapAsync({2, "broken", "p2i"}));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (core.Counter("swap_failures") == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  CHECK(core.Counter("swap_failures") == 1);
  CHECK(core.CurrentVersion() == 1);
  CHECK(core.LastSwapError().find("broken") != std::string::npos);
  msgs::RenderReplyMsg reply;
  core.HandleRender(Request({0.0}), SynthesizerCore::Clock::now(), &reply);
  CHECK(CheckOneModel(reply) == 1);
  REQUIRE(core.SwapAsync({3, "v3", "p2i"}));
  REQUIRE(core.WaitForVersion(3, std::chrono::seconds(10)));
  core.HandleRender(Request({0.0}), SynthesizerCore::Clock::now(), &reply);
  CHECK(CheckOneModel(reply) == 3);

  // A bogus announcement far ahead that fails to load does not block the real versions after
  // it (they are lower than it but newer than the serving one).
  REQUIRE(core.SwapAsync({1000, "broken", "p2i"}));
  const auto deadline2 = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (core.Counter("swap_failures") < 2 && std::chrono::steady_clock::now() < deadline2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  REQUIRE(core.Counter("swap_failures") == 2);
  REQUIRE(core.SwapAsync({4, "v4", "p2i"}));
  REQUIRE(core.WaitForVersion(4, std::chrono::seconds(10)));
  CHECK(core.CurrentVersion() == 4);
}

TEST_CASE("LatestSlot keeps only the newest item", "[unit]") {
  LatestSlot<int> slot;
  CHECK_FALSE(slot.Put(1));
  CHECK(slot.Put(2));  // replaced 1
  CHECK(slot.Put(3));
  auto got = slot.Take(std::chrono::milliseconds(10));
  REQUIRE(got);
  CHECK(*got == 3);
  CHECK_FALSE(slot.Take(std::chrono::milliseconds(1)));
  slot.Close();
  CHECK_FALSE(slot.Put(4));
  CHECK_FALSE(slot.Take(std::chrono::milliseconds(1)));
}

TEST_CASE("Topic mode under overload renders the newest pose and counts the skipped ones",
          "[unit]") {
  SynthesizerCoreOptions options;
  options.method = "nearest";
  SynthesizerCore core(options, FakeLoader(std::chrono::milliseconds(15)), LineCoverage());
  core.LoadNow({3, "", "nearest"});
  std::mutex mutex;
  std::vector<msgs::View> published;
  TopicRenderer topic(&core, [&](msgs::View&& v) {
    std::lock_guard<std::mutex> lock(mutex);
    published.push_back(std::move(v));
  });
  constexpr int kJobs = 40;
  for (int i = 0; i < kJobs; ++i) {
    PoseJob job;
    job.pose = PoseAtX(0.01 * i);
    job.request_id = static_cast<uint64_t>(i);
    job.receipt = SynthesizerCore::Clock::now();
    topic.Submit(job);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));  // faster than renders
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!topic.Idle() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  REQUIRE(topic.Idle());
  size_t before = 0;
  {
    std::lock_guard<std::mutex> lock(mutex);
    before = published.size();
  }
  const uint64_t skipped = core.Counter("skipped");
  CHECK(skipped > 0);
  CHECK(published.size() == topic.Rendered());
  CHECK(skipped + published.size() == static_cast<uint64_t>(kJobs));  // nothing else lost
  REQUIRE_FALSE(published.empty());
  // The newest request is always served, and requests are served in order.
  CHECK(published.back().meta.header().request_id() == kJobs - 1);
  for (size_t i = 1; i < published.size(); ++i) {
    CHECK(published[i].meta.header().request_id() > published[i - 1].meta.header().request_id());
  }
  for (const auto& v : published) {
    CHECK(v.meta.model_version() == 3);
    CHECK(Depth(v.depth) ==
          Approx(0.01 * static_cast<double>(v.meta.header().request_id()) + 1.0));
  }

  // A job whose deadline has passed is dropped and counted, not rendered.
  PoseJob late;
  late.pose = PoseAtX(0.0);
  late.deadline_ns = 1;
  late.receipt = SynthesizerCore::Clock::now();
  topic.Submit(late);
  const auto d2 = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!topic.Idle() && std::chrono::steady_clock::now() < d2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::lock_guard<std::mutex> lock(mutex);
  CHECK(core.Counter("expired") == 1);
  CHECK(published.size() == before);
}

}  // namespace
}  // namespace p2i::nodes

namespace p2i::nodes {
namespace {

TEST_CASE("Each model's views are scored against that model's training poses", "[unit]") {
  const std::string dir = std::filesystem::temp_directory_path() /
                          ("p2i_synth_cov_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  // Model 2 was trained around x = 5 (the start-up coverage is the line x = 0 .. 0.9).
  std::vector<scene::StampedPose> far;
  for (int i = 0; i < 10; ++i)
    far.push_back({0.1 * i, scene::Pose(Eigen::Vector3d(5.0 + 0.1 * i, 0.0, 1.0),
                                        Eigen::Quaterniond::Identity())});
  scene::WriteTumTrajectory(dir + "/v2.poses.txt", far);

  SynthesizerCore core({}, FakeLoader(), LineCoverage());
  core.LoadNow({1, "v1", "p2i"});
  msgs::RenderReplyMsg reply;
  core.HandleRender(Request({0.3, 5.3}), SynthesizerCore::Clock::now(), &reply);
  REQUIRE(CheckOneModel(reply) == 1);
  CHECK(reply.meta.views(0).coverage() == Approx(1.0));
  CHECK(reply.meta.views(1).coverage() < 0.1);

  REQUIRE(core.SwapAsync({2, "v2", "p2i", dir + "/v2.poses.txt"}));
  REQUIRE(core.WaitForVersion(2, std::chrono::seconds(10)));
  core.HandleRender(Request({0.3, 5.3}), SynthesizerCore::Clock::now(), &reply);
  REQUIRE(CheckOneModel(reply) == 2);
  CHECK(reply.meta.views(0).coverage() < 0.1);
  CHECK(reply.meta.views(1).coverage() == Approx(1.0));

  // Unreadable poses: the model still swaps in, scored against the start-up poses, counted.
  REQUIRE(core.SwapAsync({3, "v3", "p2i", dir + "/missing.poses.txt"}));
  REQUIRE(core.WaitForVersion(3, std::chrono::seconds(10)));
  CHECK(core.Counter("coverage_fallbacks") == 1);
  CHECK(core.LastSwapError().find("missing.poses.txt") != std::string::npos);
  core.HandleRender(Request({0.3, 5.3}), SynthesizerCore::Clock::now(), &reply);
  REQUIRE(CheckOneModel(reply) == 3);
  CHECK(reply.meta.views(0).coverage() == Approx(1.0));
  CHECK(reply.meta.views(1).coverage() < 0.1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace p2i::nodes
