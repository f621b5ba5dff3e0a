/// @file rgbd_frame.cc
/// @brief RgbdFrame message -> scene::RgbdSample.
#include "convert/rgbd_frame.h"

#include <string>

#include "convert/depth.h"
#include "convert/image.h"
#include "convert/pose.h"

namespace p2i::convert {

scene::RgbdSample ToSample(const msgs::RgbdFrame& frame) {
  scene::RgbdSample s;
  const auto& h = frame.meta.header();
  s.stamp = static_cast<double>(h.capture_stamp_ns()) * 1e-9;
  s.id = std::to_string(h.seq());
  if (frame.meta.has_pose()) s.pose = FromMsg(frame.meta.pose());
  s.rgb = RgbToMat(frame.rgb);
  s.depth = DepthToMetres(frame.depth);
  return s;
}

}  // namespace p2i::convert
