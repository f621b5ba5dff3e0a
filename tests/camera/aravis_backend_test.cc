/// @file aravis_backend_test.cc
/// @brief The Aravis backend in-process against Aravis' fake camera ("Fake_1"): sizes, pixel
/// format conversion (the fake's known ramp), the Mono16 depth device, clear errors.
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include <catch2/catch.hpp>

#include "nodes/camera/live_backend.h"

namespace p2i::nodes {
namespace {

#ifdef P2I_HAVE_ARAVIS

/// Streams until `count` frames arrived (or `timeout`), then stops.
std::vector<LiveFrame> Grab(LiveBackend* backend, size_t count,
                            std::chrono::seconds timeout = std::chrono::seconds(10)) {
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<LiveFrame> frames;
  std::string error;
  backend->Start(
      [&](LiveFrame&& f) {
        std::lock_guard<std::mutex> lock(mutex);
        if (frames.size() < count) frames.push_back(std::move(f));
        cv.notify_all();
      },
      [&](const std::string& e) {
        std::lock_guard<std::mutex> lock(mutex);
        error = e;
        cv.notify_all();
      });
  {
    std::unique_lock<std::mutex> lock(mutex);
    cv.wait_for(lock, timeout, [&] { return frames.size() >= count || !error.empty(); });
  }
  backend->Stop();
  INFO(error);
  CHECK(error.empty());
  return frames;
}

AravisOptions Fake(const std::string& format) {
  AravisOptions o;
  o.device = "Fake_1";
  o.pixel_format = format;
  o.width = 64;
  o.height = 48;
  o.frame_rate = 100.0;
  o.exposure_us = 10000.0;  // the fake's ramp gain is 1 at 10 ms
  return o;
}

TEST_CASE("Aravis fake camera: Mono8 frames are the fake's ramp, as grey RGB8", "[unit]") {
  auto backend = OpenAravisBackend(Fake("Mono8"));
  CHECK(backend->width() == 64);
  CHECK(backend->height() == 48);
  CHECK(backend->Describe().find("Fake_1") != std::string::npos);
  const auto frames = Grab(backend.get(), 3);
  REQUIRE(frames.size() == 3);
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::system_clock::now().time_since_epoch()).count();
  for (const LiveFrame& f : frames) {
    REQUIRE(f.rgb.type() == CV_8UC3);
    REQUIRE(f.rgb.size() == cv::Size(64, 48));
    CHECK(f.depth.empty());
    // Stamped on the system clock, at capture.
    CHECK(f.stamp_ns <= now);
    CHECK(now - f.stamp_ns < int64_t{10'000'000'000});
    // The fake fills Mono8 with (x + y + frame_id) % 255.
    int wrong = 0;
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; ++x) {
        const cv::Vec3b p = f.rgb.at<cv::Vec3b>(y, x);
        const int expect = static_cast<int>((x + y + f.frame_id) % 255);
        if (p[0] != expect || p[1] != expect || p[2] != expect) ++wrong;
      }
    }
    CHECK(wrong == 0);
  }
  CHECK(frames[1].stamp_ns > frames[0].stamp_ns);
  CHECK(backend->GetStats().frames >= 3);
}

TEST_CASE("Aravis fake camera: Mono16, RGB8 and Bayer convert to RGB8", "[unit]") {
  {
    auto backend = OpenAravisBackend(Fake("Mono16"));
    const auto frames = Grab(backend.get(), 1);
    REQUIRE(frames.size() == 1);
    const LiveFrame& f = frames[0];
    // Mono16 ramp (256 (x + y + id)) % 65535, shown as value / 257.
    const auto expect = [&](int x, int y) {
      const double v = static_cast<double>((256 * (x + y + f.frame_id)) % 65535);
      return cv::saturate_cast<uint8_t>(v / 257.0);
    };
    for (const auto& [x, y] : {std::pair{0, 0}, std::pair{10, 5}, std::pair{63, 47}}) {
      CHECK(f.rgb.at<cv::Vec3b>(y, x)[1] == expect(x, y));
    }
  }
  for (const char* format : {"RGB8", "BayerRG8", "BayerGR8"}) {
    INFO(format);
    auto backend = OpenAravisBackend(Fake(format));
    CHECK(backend->Describe().find(format) != std::string::npos);
    const auto frames = Grab(backend.get(), 1);
    REQUIRE(frames.size() == 1);
    const cv::Mat& rgb = frames[0].rgb;
    REQUIRE(rgb.size() == cv::Size(64, 48));
    REQUIRE(rgb.type() == CV_8UC3);
    // The fake paints a jet colour map along the diagonal: colour, not grey.
    int coloured = 0;
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; ++x) {
        const cv::Vec3b p = rgb.at<cv::Vec3b>(y, x);
        if (std::abs(p[0] - p[2]) > 40) ++coloured;
      }
    }
    CHECK(coloured > 64 * 48 / 4);
  }
}

TEST_CASE("Aravis fake camera: a second device gives Mono16 depth in metres", "[unit]") {
  AravisOptions o = Fake("RGB8");
  o.frame_rate = 50.0;
  o.depth_device = "Fake_1";  // a second in-process fake camera
  o.depth_scale = 0.001;
  o.depth_tolerance = 0.03;
  auto backend = OpenAravisBackend(o);
  CHECK(backend->Describe().find("depth") != std::string::npos);
  const auto frames = Grab(backend.get(), 4);
  REQUIRE(frames.size() == 4);
  int with_depth = 0;
  for (const LiveFrame& f : frames) {
    if (f.depth.empty()) continue;
    ++with_depth;
    REQUIRE(f.depth.type() == CV_32FC1);
    REQUIRE(f.depth.size() == f.rgb.size());
    // The fake fills Mono16 with (256 (x + y + id)) % 65535 (units of depth_scale = 1 mm);
    // 256 is its own inverse mod 65535, which gives id from pixel (0, 0).
    const auto raw = [&](int x, int y) {
      return static_cast<int64_t>(std::llround(f.depth.at<float>(y, x) / 0.001));
    };
    const int64_t id = (raw(0, 0) * 256) % 65535;
    int wrong = 0;
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; ++x) {
        if (raw(x, y) != (256 * (x + y + id)) % 65535) ++wrong;
      }
    }
    CHECK(wrong == 0);
    double lo = 0.0, hi = 0.0;
    cv::minMaxLoc(f.depth, &lo, &hi);
    CHECK(hi > lo);
    CHECK(hi < 65.536);
  }
  CHECK(with_depth >= 3);  // same rate, same clock: pairs within the tolerance
}

TEST_CASE("Aravis backend errors name the device and what it accepts", "[unit]") {
  AravisOptions o = Fake("Mono8");
  o.device = "Fake_1_no_such_camera";
  try {
    OpenAravisBackend(o);
    FAIL("opened a missing device");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    CHECK(what.find("Fake_1_no_such_camera") != std::string::npos);
    CHECK(what.find("devices found") != std::string::npos);
    CHECK(what.find("Fake_1") != std::string::npos);  // the list names the fake that exists
  }
  o = Fake("YUV422_8");
  CHECK_THROWS_WITH(OpenAravisBackend(o), Catch::Contains("YUV422_8") &&
                                              Catch::Contains("supported: Mono8"));
  o = Fake("BGR8");  // p2i converts it, but the fake camera does not offer it
  CHECK_THROWS_WITH(OpenAravisBackend(o),
                    Catch::Contains("does not offer pixel format 'BGR8'") &&
                        Catch::Contains("Mono16"));
  o = Fake("Mono8");
  o.width = 100000;
  CHECK_THROWS_WITH(OpenAravisBackend(o), Catch::Contains("outside the device's range"));
  o = Fake("Mono8");
  o.frame_rate = 5000.0;
  CHECK_THROWS_WITH(OpenAravisBackend(o), Catch::Contains("frame_rate"));
}

#else  // !P2I_HAVE_ARAVIS

TEST_CASE("Without Aravis the backend says it was built without it", "[unit]") {
  CHECK_FALSE(HaveAravis());
  CHECK_THROWS_WITH(OpenAravisBackend(AravisOptions()), Catch::Contains("built without Aravis"));
}

#endif

}  // namespace
}  // namespace p2i::nodes
