/// @file pixel_convert_test.cc
/// @brief Camera pixel formats to RGB8 and Mono16 to metres, with exact values.
#include <cstring>
#include <vector>

#include <catch2/catch.hpp>

#include "nodes/camera/pixel_convert.h"

namespace p2i::nodes {
namespace {

cv::Vec3b At(const cv::Mat& m, int x, int y) { return m.at<cv::Vec3b>(y, x); }

TEST_CASE("Mono8, Mono16, RGB8 and BGR8 convert to RGB8 exactly", "[unit]") {
  const std::vector<uint8_t> mono8 = {0, 10, 200, 255};
  cv::Mat rgb = ToRgb8(mono8.data(), mono8.size(), 2, 2, PixelFormat::kMono8);
  REQUIRE(rgb.type() == CV_8UC3);
  REQUIRE(rgb.size() == cv::Size(2, 2));
  CHECK(At(rgb, 1, 0) == cv::Vec3b(10, 10, 10));
  CHECK(At(rgb, 0, 1) == cv::Vec3b(200, 200, 200));

  const std::vector<uint16_t> mono16 = {0, 257, 12850, 65535};  // -> 0, 1, 50, 255
  std::vector<uint8_t> bytes(8);
  std::memcpy(bytes.data(), mono16.data(), 8);  // little-endian host, as GenICam Mono16
  rgb = ToRgb8(bytes.data(), bytes.size(), 2, 2, PixelFormat::kMono16);
  CHECK(At(rgb, 0, 0) == cv::Vec3b(0, 0, 0));
  CHECK(At(rgb, 1, 0) == cv::Vec3b(1, 1, 1));
  CHECK(At(rgb, 0, 1) == cv::Vec3b(50, 50, 50));
  CHECK(At(rgb, 1, 1) == cv::Vec3b(255, 255, 255));

  const std::vector<uint8_t> px = {1, 2, 3, 4, 5, 6};  // 2x1
  rgb = ToRgb8(px.data(), px.size(), 2, 1, PixelFormat::kRGB8);
  CHECK(At(rgb, 1, 0) == cv::Vec3b(4, 5, 6));
  rgb = ToRgb8(px.data(), px.size(), 2, 1, PixelFormat::kBGR8);
  CHECK(At(rgb, 1, 0) == cv::Vec3b(6, 5, 4));
}

/// A mosaic of a uniform colour: the top-left 2x2 cell is `pattern` ("RGGB" ...).
std::vector<uint8_t> Mosaic(const std::string& pattern, int w, int h, cv::Vec3b rgb) {
  std::vector<uint8_t> out(w * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const char c = pattern[(y % 2) * 2 + (x % 2)];
      out[y * w + x] = c == 'R' ? rgb[0] : (c == 'G' ? rgb[1] : rgb[2]);
    }
  }
  return out;
}

TEST_CASE("Bayer formats demosaic to the right colours (GenICam names)", "[unit]") {
  const cv::Vec3b colour(200, 100, 50);
  const std::pair<PixelFormat, const char*> cases[] = {
      {PixelFormat::kBayerRG8, "RGGB"},
      {PixelFormat::kBayerGR8, "GRBG"},
      {PixelFormat::kBayerGB8, "GBRG"},
      {PixelFormat::kBayerBG8, "BGGR"},
  };
  for (const auto& [format, pattern] : cases) {
    INFO(ToString(format));
    const auto raw = Mosaic(pattern, 8, 6, colour);
    const cv::Mat rgb = ToRgb8(raw.data(), raw.size(), 8, 6, format);
    REQUIRE(rgb.size() == cv::Size(8, 6));
    for (int y = 1; y < 5; ++y) {
      for (int x = 1; x < 7; ++x) CHECK(At(rgb, x, y) == colour);
    }
  }
}

TEST_CASE("Mono16 depth scales to metres, 0 stays invalid, short buffers are errors",
          "[unit]") {
  const std::vector<uint16_t> raw = {0, 1000, 1500, 65535};
  std::vector<uint8_t> bytes(8);
  std::memcpy(bytes.data(), raw.data(), 8);
  const cv::Mat d = Mono16ToDepth(bytes.data(), bytes.size(), 2, 2, 0.001);
  REQUIRE(d.type() == CV_32FC1);
  CHECK(d.at<float>(0, 0) == 0.0f);
  CHECK(d.at<float>(0, 1) == Approx(1.0));
  CHECK(d.at<float>(1, 0) == Approx(1.5));
  CHECK(d.at<float>(1, 1) == Approx(65.535));
  CHECK_THROWS_AS(Mono16ToDepth(bytes.data(), 7, 2, 2, 0.001), std::invalid_argument);
  CHECK_THROWS_AS(ToRgb8(bytes.data(), 8, 2, 2, PixelFormat::kRGB8), std::invalid_argument);
}

TEST_CASE("Pixel format names parse and print (GenICam spelling)", "[unit]") {
  for (const char* name : {"Mono8", "Mono16", "RGB8", "BGR8", "BayerRG8", "BayerGR8",
                           "BayerGB8", "BayerBG8"}) {
    const auto f = ParsePixelFormat(name);
    REQUIRE(f.has_value());
    CHECK(std::string(ToString(*f)) == name);
    CHECK(SupportedPixelFormats().find(name) != std::string::npos);
  }
  CHECK_FALSE(ParsePixelFormat("mono8").has_value());
  CHECK_FALSE(ParsePixelFormat("YUV422_8").has_value());
}

}  // namespace
}  // namespace p2i::nodes
