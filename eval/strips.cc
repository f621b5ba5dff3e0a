/// @file strips.cc
#include "eval/strips.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "scene/dataset_index.h"

namespace p2i::eval {
namespace fs = std::filesystem;

void WritePngAtomic(const std::string& path, const cv::Mat& image) {
  const std::string tmp = path + ".tmp." + std::to_string(getpid()) + ".png";
  if (!cv::imwrite(tmp, image)) {
    fs::remove(tmp);
    throw std::runtime_error("cannot write image " + path);
  }
  fs::rename(tmp, path);
}

void SaveStripView(const std::string& dir, int k, const scene::RgbdSample& view) {
  fs::create_directories(dir);
  cv::Mat bgr;
  cv::cvtColor(view.rgb, bgr, cv::COLOR_RGB2BGR);
  WritePngAtomic(dir + "/" + std::to_string(k) + "_rgb.png", bgr);
  if (!view.depth.empty())
    WritePngAtomic(dir + "/" + std::to_string(k) + "_depth.png",
                   scene::DepthToMillimetres(view.depth));
}

cv::Mat ColorMapDepth(const cv::Mat& depth_m, double max_depth_m) {
  cv::Mat scaled(depth_m.size(), CV_8UC1);
  const double m = max_depth_m > 0 ? max_depth_m : 1.0;
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const float d = depth_m.at<float>(y, x);
      scaled.at<uint8_t>(y, x) =
          static_cast<uint8_t>(std::clamp(d / m, 0.0, 1.0) * 254.0 + 1.0);  // 1..255
    }
  cv::Mat color;
  cv::applyColorMap(scaled, color, cv::COLORMAP_TURBO);
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const float d = depth_m.at<float>(y, x);
      if (!(d > 0.0f) || !std::isfinite(d)) color.at<cv::Vec3b>(y, x) = cv::Vec3b(0, 0, 0);
    }
  return color;
}

bool ComposeStrip(const std::string& strip_dir, const std::vector<std::string>& rows, int views,
                  const std::string& out_png) {
  // Cell size from the first image found; small images are enlarged (nearest) to >= 96 px.
  cv::Size native(0, 0);
  double max_depth = 0.0;
  for (const auto& r : rows)
    for (int k = 0; k < views; ++k) {
      const std::string rgb = strip_dir + "/" + r + "/" + std::to_string(k) + "_rgb.png";
      if (native.width == 0 && fs::exists(rgb)) native = cv::imread(rgb).size();
      const std::string dp = strip_dir + "/" + r + "/" + std::to_string(k) + "_depth.png";
      if (r == rows.front() && fs::exists(dp)) {
        cv::Mat d = cv::imread(dp, cv::IMREAD_UNCHANGED);
        double mn, mx;
        cv::minMaxLoc(d, &mn, &mx);
        max_depth = std::max(max_depth, mx / 1000.0);
      }
    }
  if (native.width == 0) return false;
  if (max_depth <= 0) max_depth = 5.0;
  const int scale = std::max(1, (96 + native.width - 1) / native.width);
  const cv::Size cell(native.width * scale, native.height * scale);
  const int label_w = 130, gap = 4, header = 22;
  const int width = label_w + views * (2 * cell.width + 3 * gap);
  const int height = header + static_cast<int>(rows.size()) * (cell.height + gap);
  cv::Mat canvas(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(canvas, "RGB | depth (0-" + std::to_string(static_cast<int>(max_depth * 10) / 10.0).substr(0, 4) + " m)",
              cv::Point(label_w, 15), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  for (size_t ri = 0; ri < rows.size(); ++ri) {
    const int y0 = header + static_cast<int>(ri) * (cell.height + gap);
    cv::putText(canvas, rows[ri].substr(0, 18), cv::Point(4, y0 + cell.height / 2 + 5),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    for (int k = 0; k < views; ++k) {
      const int x0 = label_w + k * (2 * cell.width + 3 * gap);
      const std::string base = strip_dir + "/" + rows[ri] + "/" + std::to_string(k);
      cv::Mat rgb = fs::exists(base + "_rgb.png") ? cv::imread(base + "_rgb.png") : cv::Mat();
      cv::Mat depth;
      if (fs::exists(base + "_depth.png")) {
        cv::Mat mm = cv::imread(base + "_depth.png", cv::IMREAD_UNCHANGED);
        cv::Mat m;
        mm.convertTo(m, CV_32F, 1.0 / 1000.0);
        depth = ColorMapDepth(m, max_depth);
      }
      for (int c = 0; c < 2; ++c) {
        cv::Mat img = c == 0 ? rgb : depth;
        cv::Rect roi(x0 + c * (cell.width + gap), y0, cell.width, cell.height);
        if (img.empty()) {
          canvas(roi).setTo(cv::Scalar(160, 160, 160));
          continue;
        }
        cv::Mat big;
        cv::resize(img, big, cell, 0, 0, cv::INTER_NEAREST);
        big.copyTo(canvas(roi));
      }
    }
  }
  fs::create_directories(fs::path(out_png).parent_path());
  WritePngAtomic(out_png, canvas);
  return true;
}

}  // namespace p2i::eval
