/// @file samples.h
/// @brief Valid sample messages of every type with pseudo-random contents, for msgs tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "convert/pose.h"
#include "msgs/codec.h"

namespace p2i::msgs::testing {

/// Deterministic source of sample values.
class Samples {
 public:
  explicit Samples(uint32_t seed) : rng_(seed) {}

  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  uint32_t Int(uint32_t lo, uint32_t hi) {
    return std::uniform_int_distribution<uint32_t>(lo, hi)(rng_);
  }
  std::mt19937& rng() { return rng_; }

  void FillHeader(pb::Header* h) {
    h->set_seq(Int(0, 1000000));
    h->set_capture_stamp_ns(1700000000000000000LL + Int(0, 1000000000));
    h->set_publish_stamp_ns(h->capture_stamp_ns() + Int(0, 1000000));
    h->set_frame_id("camera_" + std::to_string(Int(0, 9)));
    h->set_request_id(Int(0, 100000));
    h->set_publisher("/robot/node" + std::to_string(Int(0, 9)));
  }

  void FillPose(pb::Pose* p) {
    double q[4];
    double n = 0;
    for (double& v : q) {
      v = Uniform(-1, 1);
      n += v * v;
    }
    n = std::sqrt(n);
    convert::SetPose({Uniform(-5, 5), Uniform(-5, 5), Uniform(-5, 5), q[0] / n, q[1] / n,
                      q[2] / n, q[3] / n},
                     p);
    p->set_parent_frame("world");
    p->set_child_frame("camera");
  }

  void FillCameraInfo(pb::CameraInfo* c) {
    c->set_width(640);
    c->set_height(480);
    c->set_distortion_model("plumb_bob");
    for (int i = 0; i < 5; ++i) c->add_d(Uniform(-0.1, 0.1));
    const double f = Uniform(400, 600);
    for (double v : {f, 0.0, 320.0, 0.0, f, 240.0, 0.0, 0.0, 1.0}) c->add_k(v);
    for (double v : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) c->add_r(v);
    for (double v : {f, 0.0, 320.0, 0.0, 0.0, f, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0}) c->add_p(v);
    c->set_camera_name("kinect");
  }

  Image MakeImage(Encoding e, uint32_t w, uint32_t h, uint32_t pad = 0) {
    Image img = Image::Allocate(e, w, h);
    if (pad != 0) {
      img.step += pad;
      img.data = std::make_shared<const Bytes>(static_cast<size_t>(img.step) * h, 0);
    }
    uint8_t* d = img.MutableData();
    for (size_t i = 0; i < img.data->size(); ++i) d[i] = static_cast<uint8_t>(rng_());
    if (e == pb::DEPTH16U) {
      img.depth_scale = 0.001;
      img.invalid_value = 0;
    } else if (e == pb::DEPTH32F) {
      img.depth_scale = 1.0;
    }
    return img;
  }

  pb::PoseStamped MakePoseStamped() {
    pb::PoseStamped m;
    FillHeader(m.mutable_header());
    FillPose(m.mutable_pose());
    return m;
  }
  pb::CameraInfo MakeCameraInfo() {
    pb::CameraInfo m;
    FillHeader(m.mutable_header());
    FillCameraInfo(&m);
    return m;
  }
  pb::PoseRequest MakePoseRequest() {
    pb::PoseRequest m;
    FillHeader(m.mutable_header());
    m.set_request_id(Int(1, 1000));
    FillPose(m.mutable_pose());
    m.set_deadline_ns(Int(0, 1000000));
    return m;
  }
  pb::ModelVersion MakeModelVersion() {
    pb::ModelVersion m;
    FillHeader(m.mutable_header());
    m.set_version(Int(1, 100));
    m.set_checkpoint_path("/tmp/ckpt_" + std::to_string(Int(0, 99)) + ".pt");
    m.set_step(Int(0, 100000));
    m.set_method("p2i");
    m.set_val_psnr(Uniform(10, 30));
    m.set_val_ssim(Uniform(0, 1));
    m.set_val_lpips(Uniform(0, 1));
    m.set_width(128);
    m.set_height(128);
    return m;
  }
  pb::TrainerStatus MakeTrainerStatus() {
    pb::TrainerStatus m;
    FillHeader(m.mutable_header());
    m.set_step(Int(0, 100000));
    (*m.mutable_losses())["l1"] = Uniform(0, 1);
    (*m.mutable_losses())["gan"] = Uniform(0, 1);
    m.set_steps_per_s(Uniform(0, 50));
    m.set_buffer_size(Int(0, 5000));
    m.set_phase("training");
    return m;
  }
  pb::NodeStatus MakeNodeStatus() {
    pb::NodeStatus m;
    FillHeader(m.mutable_header());
    m.set_node("/robot/camera");
    m.set_alive(true);
    m.set_uptime_s(Uniform(0, 1000));
    (*m.mutable_counters())["published"] = Int(0, 100000);
    (*m.mutable_counters())["dropped"] = Int(0, 10);
    (*m.mutable_values())["rate_hz"] = Uniform(0, 60);
    return m;
  }
  pb::RenderRequest MakeRenderRequest(int n = 3) {
    pb::RenderRequest m;
    FillHeader(m.mutable_header());
    m.set_request_id(Int(1, 1000));
    for (int i = 0; i < n; ++i) FillPose(m.add_poses());
    m.set_deadline_ns(Int(0, 1000000));
    m.set_method("p2i");
    return m;
  }
  void FillViewMeta(pb::ViewMeta* v) {
    FillPose(v->mutable_pose());
    v->set_model_version(Int(1, 50));
    v->set_coverage(Uniform(0, 1));
    v->set_queue_ms(Uniform(0, 5));
    v->set_render_ms(Uniform(0, 50));
    v->set_method("p2i");
  }
  RenderReplyMsg MakeRenderReply(int n = 2, uint32_t w = 8, uint32_t h = 6) {
    RenderReplyMsg m;
    FillHeader(m.meta.mutable_header());
    m.meta.set_request_id(Int(1, 1000));
    m.meta.set_ok(true);
    for (int i = 0; i < n; ++i) {
      FillViewMeta(m.meta.add_views());
      m.images.push_back(MakeImage(pb::RGB8, w, h));
      m.images.push_back(MakeImage(pb::DEPTH32F, w, h));
    }
    return m;
  }
  msgs::RgbdFrame MakeRgbdFrame(uint32_t w = 16, uint32_t h = 12) {
    msgs::RgbdFrame m;
    FillHeader(m.meta.mutable_header());
    FillCameraInfo(m.meta.mutable_camera_info());
    FillPose(m.meta.mutable_pose());
    m.rgb = MakeImage(pb::RGB8, w, h);
    m.depth = MakeImage(pb::DEPTH16U, w, h);
    return m;
  }
  msgs::View MakeView(uint32_t w = 16, uint32_t h = 12) {
    msgs::View m;
    FillHeader(m.meta.mutable_header());
    FillPose(m.meta.mutable_pose());
    m.meta.set_model_version(Int(1, 50));
    m.meta.set_coverage(Uniform(0, 1));
    m.meta.set_queue_ms(Uniform(0, 5));
    m.meta.set_render_ms(Uniform(0, 50));
    m.meta.set_method("p2i");
    m.rgb = MakeImage(pb::RGB8, w, h);
    m.depth = MakeImage(pb::DEPTH32F, w, h);
    return m;
  }

 private:
  std::mt19937 rng_;
};

}  // namespace p2i::msgs::testing
