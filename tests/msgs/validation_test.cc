/// @file validation_test.cc
/// @brief Each rejection reason of the decoders, the counters, and what is accepted and fixed.
#include <catch2/catch.hpp>

#include <atomic>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "convert/pose.h"
#include "msgs/codec.h"
#include "tests/msgs/samples.h"

namespace p2i::msgs {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Re-serializes the header frame of `wire` after `edit` changed its metadata (as a hostile or
/// buggy sender would), bypassing Encode.
template <class Pb, class Edit>
WireMessage EditMeta(WireMessage wire, Edit edit) {
  Pb meta;
  REQUIRE(meta.ParseFromString(wire.header));
  edit(meta);
  wire.header = meta.SerializeAsString();
  return wire;
}

/// Decodes as T and requires a rejection with `expected`, a message naming `field`, the output
/// untouched and the counter of that reason incremented by one.
template <class T>
void CheckRejected(const WireMessage& wire, DecodeReason expected, const std::string& field) {
  const uint64_t before = DecodeStats::Global().Get(expected);
  const uint64_t ok_before = DecodeStats::Global().Get(DecodeReason::kOk);
  T out;
  MutableHeader(out)->set_frame_id("untouched");
  std::string error;
  DecodeReason reason = DecodeReason::kOk;
  CHECK_FALSE(Decode(wire, &out, &error, &reason));
  INFO("error: " << error);
  CHECK(reason == expected);
  CHECK(error.rfind(std::string(DecodeReasonName(expected)) + ": ", 0) == 0);
  CHECK(error.find(field) != std::string::npos);
  CHECK(error.find('\n') == std::string::npos);
  CHECK(GetHeader(out).frame_id() == "untouched");
  CHECK(DecodeStats::Global().Get(expected) == before + 1);
  CHECK(DecodeStats::Global().Get(DecodeReason::kOk) == ok_before);
}

pb::PoseStamped PoseWithQuaternionScale(double scale) {
  pb::PoseStamped m;
  convert::SetPose({1, 2, 3, 0.5 * scale, -0.5 * scale, 0.5 * scale, 0.5 * scale},
                   m.mutable_pose());
  return m;
}

TEST_CASE("quaternion norm: 1.01 rejected, 1.0005 accepted and normalised", "[unit]") {
  CheckRejected<pb::PoseStamped>(Encode(PoseWithQuaternionScale(1.01)),
                                 DecodeReason::kBadQuaternion, "pose.orientation");
  CheckRejected<pb::PoseStamped>(Encode(PoseWithQuaternionScale(0.99)),
                                 DecodeReason::kBadQuaternion, "pose.orientation");
  CheckRejected<pb::PoseStamped>(Encode(PoseWithQuaternionScale(0.0)),
                                 DecodeReason::kBadQuaternion, "pose.orientation");
  for (double scale : {1.0005, 0.9995}) {
    pb::PoseStamped out;
    std::string error;
    REQUIRE(Decode(Encode(PoseWithQuaternionScale(scale)), &out, &error));
    const auto& q = out.pose().orientation();
    CHECK(std::sqrt(q.x() * q.x() + q.y() * q.y() + q.z() * q.z() + q.w() * q.w()) ==
          Approx(1.0).margin(1e-12));
    CHECK(q.x() == Approx(0.5).margin(1e-12));
    CHECK(q.y() == Approx(-0.5).margin(1e-12));
  }
  SECTION("missing orientation or pose") {
    pb::PoseStamped m;
    m.mutable_pose()->mutable_position()->set_x(1);
    CheckRejected<pb::PoseStamped>(Encode(m), DecodeReason::kBadQuaternion, "pose.orientation");
    CheckRejected<pb::PoseStamped>(Encode(pb::PoseStamped()), DecodeReason::kBadValue, "pose");
  }
  SECTION("in every pose-carrying type") {
    testing::Samples s(11);
    auto bad = [](pb::Pose* p) {
      auto* q = p->mutable_orientation();
      q->set_x(q->x() * 1.1);
      q->set_y(q->y() * 1.1);
      q->set_z(q->z() * 1.1);
      q->set_w(q->w() * 1.1);
    };
    auto req = s.MakeRenderRequest(3);
    bad(req.mutable_poses(2));
    CheckRejected<pb::RenderRequest>(Encode(req), DecodeReason::kBadQuaternion, "poses[2]");
    auto pr = s.MakePoseRequest();
    bad(pr.mutable_pose());
    CheckRejected<pb::PoseRequest>(Encode(pr), DecodeReason::kBadQuaternion, "pose.orientation");
    auto view = s.MakeView();
    bad(view.meta.mutable_pose());
    CheckRejected<View>(Encode(view), DecodeReason::kBadQuaternion, "pose.orientation");
    auto frame = s.MakeRgbdFrame();
    bad(frame.meta.mutable_pose());
    CheckRejected<RgbdFrame>(Encode(frame), DecodeReason::kBadQuaternion, "pose.orientation");
    auto reply = s.MakeRenderReply(2);
    bad(reply.meta.mutable_views(1)->mutable_pose());
    CheckRejected<RenderReplyMsg>(Encode(reply), DecodeReason::kBadQuaternion, "views[1].pose");
  }
}

TEST_CASE("non-finite numbers are rejected wherever they are", "[unit]") {
  testing::Samples s(12);
  auto pose = s.MakePoseStamped();
  pose.mutable_pose()->mutable_position()->set_y(kNaN);
  CheckRejected<pb::PoseStamped>(Encode(pose), DecodeReason::kNonFinite, "pose.position.y");
  auto cam = s.MakeCameraInfo();
  cam.set_k(2, kInf);
  CheckRejected<pb::CameraInfo>(Encode(cam), DecodeReason::kNonFinite, "k[2]");
  auto trainer = s.MakeTrainerStatus();
  (*trainer.mutable_losses())["l1"] = kNaN;
  CheckRejected<pb::TrainerStatus>(Encode(trainer), DecodeReason::kNonFinite, "losses");
  auto status = s.MakeNodeStatus();
  (*status.mutable_values())["rate_hz"] = -kInf;
  CheckRejected<pb::NodeStatus>(Encode(status), DecodeReason::kNonFinite, "values");
  auto model = s.MakeModelVersion();
  model.set_val_psnr(kInf);
  CheckRejected<pb::ModelVersion>(Encode(model), DecodeReason::kNonFinite, "val_psnr");
  auto view = s.MakeView();
  view.meta.set_render_ms(kNaN);
  CheckRejected<View>(Encode(view), DecodeReason::kNonFinite, "render_ms");
  auto frame = s.MakeRgbdFrame();
  frame.depth.depth_scale = kNaN;
  CheckRejected<RgbdFrame>(Encode(frame), DecodeReason::kNonFinite, "depth.depth_scale");
  frame = s.MakeRgbdFrame();
  frame.depth.invalid_value = kInf;
  CheckRejected<RgbdFrame>(Encode(frame), DecodeReason::kNonFinite, "depth.invalid_value");
}

TEST_CASE("header checks: unparsable, unknown type, version, type mismatch", "[unit]") {
  testing::Samples s(13);
  const WireMessage wire = Encode(s.MakePoseStamped());
  CheckRejected<pb::PoseStamped>(WireMessage{"\x0a\xff\xff\xff", {}}, DecodeReason::kUnparsable,
                                 "header");
  CheckRejected<pb::PoseStamped>(WireMessage{"", {}}, DecodeReason::kUnparsable, "header");
  CheckRejected<pb::PoseStamped>(
      EditMeta<pb::PoseStamped>(wire, [](auto& m) { m.mutable_header()->set_type(pb::MsgType(99)); }),
      DecodeReason::kUnknownType, "header.type");
  CheckRejected<pb::PoseStamped>(
      EditMeta<pb::PoseStamped>(wire, [](auto& m) { m.mutable_header()->set_type(pb::MSG_UNKNOWN); }),
      DecodeReason::kUnknownType, "header.type");
  for (uint32_t version : {0u, kSchemaVersion + 1}) {
    CheckRejected<pb::PoseStamped>(EditMeta<pb::PoseStamped>(wire,
                                                             [&](auto& m) {
                                                               m.mutable_header()
                                                                   ->set_schema_version(version);
                                                             }),
                                   DecodeReason::kBadVersion, "header.schema_version");
  }
  CheckRejected<pb::NodeStatus>(wire, DecodeReason::kTypeMismatch, "header.type");
  CheckRejected<View>(wire, DecodeReason::kTypeMismatch, "expected View");

  pb::Header h;
  std::string error;
  CHECK(PeekHeader(wire.header, &h, &error));
  CHECK(h.type() == pb::POSE);
  CHECK_FALSE(PeekHeader("\x0a\x05\x08", &h, &error));
  CHECK_FALSE(error.empty());
}

TEST_CASE("blob frames: missing, null, extra, wrong size", "[unit]") {
  testing::Samples s(14);
  const RgbdFrame frame = s.MakeRgbdFrame(16, 12);
  const WireMessage good = Encode(frame);

  WireMessage w = good;
  w.blobs.pop_back();
  CheckRejected<RgbdFrame>(w, DecodeReason::kMissingBlob, "depth.blob_index");
  w = good;
  w.blobs.clear();
  CheckRejected<RgbdFrame>(w, DecodeReason::kMissingBlob, "rgb.blob_index");
  w = good;
  w.blobs[1] = nullptr;
  CheckRejected<RgbdFrame>(w, DecodeReason::kMissingBlob, "depth");
  w = good;
  w.blobs.push_back(std::make_shared<const Bytes>(10, 0));
  CheckRejected<RgbdFrame>(w, DecodeReason::kExtraBlob, "blob frame 2");
  w = good;
  w.blobs[0] = std::make_shared<const Bytes>(16 * 12 * 3 - 1, 0);
  CheckRejected<RgbdFrame>(w, DecodeReason::kBlobSize, "rgb");
  w = good;
  w.blobs[1] = std::make_shared<const Bytes>(16 * 12 * 2 + 2, 0);
  CheckRejected<RgbdFrame>(w, DecodeReason::kBlobSize, "depth");
  w = good;
  std::swap(w.blobs[0], w.blobs[1]);
  CheckRejected<RgbdFrame>(w, DecodeReason::kBlobSize, "rgb");

  CheckRejected<pb::PoseStamped>(WireMessage{Encode(s.MakePoseStamped()).header, good.blobs},
                                 DecodeReason::kExtraBlob, "blob frame");

  const RenderReplyMsg reply = s.MakeRenderReply(2);
  w = Encode(reply);
  w.blobs.pop_back();
  CheckRejected<RenderReplyMsg>(w, DecodeReason::kMissingBlob, "views[1].depth");
  w = Encode(reply.meta);  // no images, but the blobs arrive anyway
  w.blobs = Encode(reply).blobs;
  CheckRejected<RenderReplyMsg>(w, DecodeReason::kBadImage, "views[0].rgb.encoding");
}

TEST_CASE("image geometry: sizes, step, encodings, depth scale", "[unit]") {
  testing::Samples s(15);
  const WireMessage good = Encode(s.MakeView(16, 12));
  using E = pb::View;
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_rgb()->set_width(0); }),
                      DecodeReason::kBadImage, "rgb");
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_depth()->set_height(16385); }),
                      DecodeReason::kBadImage, "depth");
  // step below width * channels: a consistent but too-small blob must still be refused.
  CheckRejected<View>(EditMeta<E>(good,
                                  [](E& m) {
                                    m.mutable_rgb()->set_width(32);
                                    m.mutable_rgb()->set_height(18);
                                    m.mutable_rgb()->set_step(32);
                                  }),
                      DecodeReason::kBadImage, "rgb.step");
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_depth()->set_step(16 * 4 + 2); }),
                      DecodeReason::kBadImage, "depth.step");
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_depth()->set_depth_scale(0); }),
                      DecodeReason::kBadImage, "depth.depth_scale");
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_rgb()->set_encoding(pb::MONO8); }),
                      DecodeReason::kBadImage, "rgb.encoding");
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_depth()->set_encoding(pb::RGB8); }),
                      DecodeReason::kBadImage, "depth.encoding");
  CheckRejected<View>(
      EditMeta<E>(good, [](E& m) { m.mutable_depth()->set_encoding(pb::Encoding(42)); }),
      DecodeReason::kBadImage, "depth.encoding");
  CheckRejected<View>(EditMeta<E>(good, [](E& m) { m.mutable_depth()->set_blob_index(0); }),
                      DecodeReason::kBadImage, "used twice");
  // A height * step larger than 32 bits must not wrap around.
  CheckRejected<View>(EditMeta<E>(good,
                                  [](E& m) {
                                    m.mutable_rgb()->set_width(16384);
                                    m.mutable_rgb()->set_height(16384);
                                    m.mutable_rgb()->set_step(0xFFFFFFFFu);
                                  }),
                      DecodeReason::kBlobSize, "rgb");
}

TEST_CASE("other values: camera info, coverage, counts, deadlines", "[unit]") {
  testing::Samples s(16);
  auto cam = s.MakeCameraInfo();
  cam.mutable_k()->RemoveLast();
  CheckRejected<pb::CameraInfo>(Encode(cam), DecodeReason::kBadValue, "k has 8 values");
  cam = s.MakeCameraInfo();
  cam.set_k(0, -500);
  CheckRejected<pb::CameraInfo>(Encode(cam), DecodeReason::kBadValue, "focal");
  cam = s.MakeCameraInfo();
  cam.set_width(0);
  CheckRejected<pb::CameraInfo>(Encode(cam), DecodeReason::kBadValue, "width");
  cam = s.MakeCameraInfo();
  cam.add_p(0);
  CheckRejected<pb::CameraInfo>(Encode(cam), DecodeReason::kBadValue, "p has 13");

  auto frame = s.MakeRgbdFrame();
  frame.meta.mutable_camera_info()->clear_k();
  CheckRejected<RgbdFrame>(Encode(frame), DecodeReason::kBadValue, "camera_info.k");
  frame.meta.clear_camera_info();
  CheckRejected<RgbdFrame>(Encode(frame), DecodeReason::kBadValue, "camera_info");

  auto view = s.MakeView();
  view.meta.set_coverage(1.5);
  CheckRejected<View>(Encode(view), DecodeReason::kBadValue, "coverage");
  view = s.MakeView();
  view.meta.set_coverage(std::nan(""));
  CheckRejected<View>(Encode(view), DecodeReason::kNonFinite, "coverage");
  // The optional geometry fields of fusion's views: checked when present, absent is fine.
  view = s.MakeView();
  view.meta.set_observed_fraction(0.8);
  view.meta.set_keyframe_angle_deg(12.5);
  {
    View out;
    std::string error;
    REQUIRE(Decode(Encode(view), &out, &error));
    CHECK(out.meta.observed_fraction() == 0.8);
    CHECK(out.meta.keyframe_angle_deg() == 12.5);
  }
  view.meta.set_observed_fraction(-0.1);
  CheckRejected<View>(Encode(view), DecodeReason::kBadValue, "observed_fraction");
  view.meta.set_observed_fraction(0.5);
  view.meta.set_keyframe_angle_deg(std::nan(""));
  CheckRejected<View>(Encode(view), DecodeReason::kNonFinite, "keyframe_angle_deg");
  view.meta.set_keyframe_angle_deg(200.0);
  CheckRejected<View>(Encode(view), DecodeReason::kBadValue, "keyframe_angle_deg");
  auto reply = s.MakeRenderReply(2);
  reply.meta.mutable_views(1)->set_observed_fraction(2.0);
  CheckRejected<RenderReplyMsg>(Encode(reply), DecodeReason::kBadValue, "views[1].observed_fraction");
  auto req = s.MakePoseRequest();
  req.set_deadline_ns(-1);
  CheckRejected<pb::PoseRequest>(Encode(req), DecodeReason::kBadValue, "deadline_ns");
  auto many = s.MakeRenderRequest(kMaxBatch + 1);
  CheckRejected<pb::RenderRequest>(Encode(many), DecodeReason::kBadValue, "poses has 4097");
  auto status = s.MakeNodeStatus();
  status.set_uptime_s(-1);
  CheckRejected<pb::NodeStatus>(Encode(status), DecodeReason::kBadValue, "uptime_s");
}

TEST_CASE("oversized messages are rejected against a settable limit", "[unit]") {
  testing::Samples s(17);
  const WireMessage wire = Encode(s.MakeRgbdFrame(64, 48));  // ~15 KB
  CHECK(MaxMessageBytes() == kDefaultMaxMessageBytes);
  SetMaxMessageBytes(WireSize(wire) - 1);
  CheckRejected<RgbdFrame>(wire, DecodeReason::kOversized, "limit");
  SetMaxMessageBytes(WireSize(wire));
  RgbdFrame out;
  std::string error;
  CHECK(Decode(wire, &out, &error));
  SetMaxMessageBytes(kDefaultMaxMessageBytes);
}

TEST_CASE("Encode refuses programmer errors", "[unit]") {
  testing::Samples s(18);
  RgbdFrame frame = s.MakeRgbdFrame();
  frame.depth.data = nullptr;
  CHECK_THROWS_AS(Encode(frame), std::invalid_argument);
  RenderReplyMsg reply = s.MakeRenderReply(2);
  reply.images.pop_back();
  CHECK_THROWS_AS(Encode(reply), std::invalid_argument);
}

TEST_CASE("decoders and counters are safe to use from many threads", "[unit]") {
  testing::Samples s(19);
  const WireMessage good = Encode(s.MakeView(32, 24));
  WireMessage bad = good;
  bad.blobs.pop_back();
  constexpr int kThreads = 4, kEach = 500;
  const uint64_t ok_before = DecodeStats::Global().Get(DecodeReason::kOk);
  const uint64_t missing_before = DecodeStats::Global().Get(DecodeReason::kMissingBlob);
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < kEach; ++i) {
        View out;
        std::string error;
        if (!Decode(good, &out, &error) || Decode(bad, &out, &error)) ++wrong;
      }
    });
  }
  for (auto& t : threads) t.join();
  CHECK(wrong == 0);
  CHECK(DecodeStats::Global().Get(DecodeReason::kOk) - ok_before == kThreads * kEach);
  CHECK(DecodeStats::Global().Get(DecodeReason::kMissingBlob) - missing_before ==
        kThreads * kEach);
}

TEST_CASE("DecodeStats snapshot names every reason", "[unit]") {
  const auto snap = DecodeStats::Global().Snapshot();
  CHECK(snap.size() == static_cast<size_t>(DecodeReason::kCount));
  CHECK(snap.count("bad_quaternion") == 1);
  CHECK(snap.count("ok") == 1);
  uint64_t rejected = 0;
  for (const auto& [name, n] : snap) rejected += name == "ok" ? 0 : n;
  CHECK(rejected == DecodeStats::Global().Rejected());
}

}  // namespace
}  // namespace p2i::msgs
