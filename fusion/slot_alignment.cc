/// @file slot_alignment.cc
/// @brief Floating textures: slots moved onto their blend (see slot_alignment.h).
#include "fusion/slot_alignment.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace p2i::fusion {
namespace {

cv::Mat Luminance8(const cv::Mat& rgb) {
  cv::Mat grey, out;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  grey.convertTo(out, CV_8U, 255.0);
  return out;
}

/// Sample positions x + flow(x), the flow shortened to `max_px`.
void ShiftMaps(const cv::Mat& flow, float max_px, cv::Mat* map_x, cv::Mat* map_y) {
  map_x->create(flow.size(), CV_32FC1);
  map_y->create(flow.size(), CV_32FC1);
  for (int v = 0; v < flow.rows; ++v) {
    const cv::Vec2f* f = flow.ptr<cv::Vec2f>(v);
    float* mx = map_x->ptr<float>(v);
    float* my = map_y->ptr<float>(v);
    for (int u = 0; u < flow.cols; ++u) {
      cv::Vec2f d = f[u];
      const float len = std::sqrt(d[0] * d[0] + d[1] * d[1]);
      if (len > max_px) d *= max_px / len;
      mx[u] = static_cast<float>(u) + d[0];
      my[u] = static_cast<float>(v) + d[1];
    }
  }
}

/// sum_j weights[j] * colours[j] where any slot is visible; `blended` elsewhere unchanged.
void Reblend(ViewCandidates* c) {
  for (int v = 0; v < c->blended.rows; ++v) {
    cv::Vec3f* out = c->blended.ptr<cv::Vec3f>(v);
    for (int u = 0; u < c->blended.cols; ++u) {
      float wsum = 0.0f;
      cv::Vec3f acc(0.0f, 0.0f, 0.0f);
      for (int j = 0; j < c->k(); ++j) {
        if (c->weights[j].empty()) continue;
        const float w = c->weights[j].at<float>(v, u);
        wsum += w;
        acc += w * c->colours[j].at<cv::Vec3f>(v, u);
      }
      if (wsum > 0.0f) out[u] = acc / wsum;
    }
  }
}

}  // namespace

int DisPreset(const std::string& name) {
  if (name == "ultrafast") return cv::DISOpticalFlow::PRESET_ULTRAFAST;
  if (name == "fast") return cv::DISOpticalFlow::PRESET_FAST;
  if (name == "medium") return cv::DISOpticalFlow::PRESET_MEDIUM;
  throw std::invalid_argument("align_flow_preset must be ultrafast, fast or medium, got '" + name + "'");
}

void AlignSlots(const SlotAlignmentOptions& options, ViewCandidates* c) {
  if (options.iterations <= 0 || c->colours.empty() || c->blended.empty()) return;
  // One flow object per thread, preset and view size, and one set of buffers per thread, kept
  // between views (as SurfaceMesh::Rasterize keeps its View). A DIS object must not see a second
  // size: it keeps state from the first (OpenCV 4.6), and a view aligned after a view of another
  // size came out different by up to 19 grey levels (test "Slot alignment: a view aligns the same
  // after a view of another size").
  thread_local std::map<std::tuple<int, int, int>, cv::Ptr<cv::DISOpticalFlow>> flows;
  thread_local cv::Mat flow, map_x, map_y, source, moved;
  const int wanted = DisPreset(options.flow_preset);
  const auto key = std::make_tuple(wanted, c->blended.cols, c->blended.rows);
  if (flows.size() >= 8 && flows.count(key) == 0) flows.clear();  // a caller cycling through sizes
  cv::Ptr<cv::DISOpticalFlow>& dis = flows[key];
  if (dis.empty()) dis = cv::DISOpticalFlow::create(wanted);
  const float max_px = static_cast<float>(options.max_shift_px);
  for (int it = 0; it < options.iterations; ++it) {
    const cv::Mat reference = Luminance8(c->blended);
    std::vector<cv::Mat> aligned(c->colours.size());
    for (int j = 0; j < c->k(); ++j) {
      if (c->colours[j].empty() || c->weights[j].empty()) continue;
      const cv::Mat visible = c->weights[j] > 0.0f;
      if (cv::countNonZero(visible) == 0) continue;
      c->blended.copyTo(source);
      c->colours[j].copyTo(source, visible);
      flow.release();
      dis->calc(reference, Luminance8(source), flow);
      ShiftMaps(flow, max_px, &map_x, &map_y);
      cv::remap(source, moved, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
      aligned[j] = cv::Mat::zeros(moved.size(), moved.type());
      moved.copyTo(aligned[j], visible);
    }
    for (int j = 0; j < c->k(); ++j)
      if (!aligned[j].empty()) c->colours[j] = aligned[j];
    Reblend(c);
  }
}

}  // namespace p2i::fusion
