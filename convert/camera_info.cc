/// @file camera_info.cc
/// @brief CameraInfo message conversions.
#include "convert/camera_info.h"

namespace p2i::convert {

void ToMsg(const scene::CameraInfo& c, msgs::pb::CameraInfo* out) {
  out->set_width(static_cast<uint32_t>(c.image_width));
  out->set_height(static_cast<uint32_t>(c.image_height));
  out->set_distortion_model(c.distortion_model);
  out->set_camera_name(c.camera_name);
  out->clear_d();
  out->clear_k();
  out->clear_r();
  out->clear_p();
  for (double d : c.distortion_coefficients) out->add_d(d);
  for (double k : c.camera_matrix) out->add_k(k);
  for (double r : c.rectification_matrix) out->add_r(r);
  for (double p : c.projection_matrix) out->add_p(p);
}

scene::CameraInfo FromMsg(const msgs::pb::CameraInfo& m) {
  scene::CameraInfo c;
  c.image_width = static_cast<int>(m.width());
  c.image_height = static_cast<int>(m.height());
  c.distortion_model = m.distortion_model();
  c.camera_name = m.camera_name();
  c.distortion_coefficients.assign(m.d().begin(), m.d().end());
  for (int i = 0; i < 9 && i < m.k_size(); ++i) c.camera_matrix[i] = m.k(i);
  for (int i = 0; i < 9 && i < m.r_size(); ++i) c.rectification_matrix[i] = m.r(i);
  for (int i = 0; i < 12 && i < m.p_size(); ++i) c.projection_matrix[i] = m.p(i);
  return c;
}

}  // namespace p2i::convert
