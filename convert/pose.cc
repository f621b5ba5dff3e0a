/// @file pose.cc
/// @brief Pose message conversions.
#include "convert/pose.h"

namespace p2i::convert {

void SetPose(const std::array<double, 7>& v, msgs::pb::Pose* pose) {
  auto* p = pose->mutable_position();
  p->set_x(v[0]);
  p->set_y(v[1]);
  p->set_z(v[2]);
  auto* q = pose->mutable_orientation();
  q->set_x(v[3]);
  q->set_y(v[4]);
  q->set_z(v[5]);
  q->set_w(v[6]);
}

std::array<double, 7> PoseVector(const msgs::pb::Pose& pose) {
  const auto& p = pose.position();
  const auto& q = pose.orientation();
  return {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()};
}

void ToMsg(const scene::Pose& pose, msgs::pb::Pose* out, const std::string& parent_frame,
           const std::string& child_frame) {
  const scene::Vector7d v = pose.ToVector7();
  SetPose({v(0), v(1), v(2), v(3), v(4), v(5), v(6)}, out);
  out->set_parent_frame(parent_frame);
  out->set_child_frame(child_frame);
}

scene::Pose FromMsg(const msgs::pb::Pose& pose) {
  const auto v = PoseVector(pose);
  scene::Vector7d x;
  for (int i = 0; i < 7; ++i) x(i) = v[i];
  return scene::Pose::FromVector7(x);
}

}  // namespace p2i::convert
