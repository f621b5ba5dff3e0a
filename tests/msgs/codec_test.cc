/// @file codec_test.cc
/// @brief Round trip of every message type through Encode / Decode, PeekHeader, DebugString.
#include "msgs/codec.h"

#include <google/protobuf/util/message_differencer.h>

#include <catch2/catch.hpp>

#include "convert/pose.h"
#include "tests/msgs/samples.h"

namespace p2i::msgs {
namespace {

using google::protobuf::util::MessageDifferencer;

/// Equal up to the last bits of doubles (decoding renormalises quaternions).
bool SameMessage(const google::protobuf::Message& a, const google::protobuf::Message& b,
                 std::string* report) {
  MessageDifferencer d;
  d.set_float_comparison(MessageDifferencer::APPROXIMATE);
  d.ReportDifferencesToString(report);
  return d.Compare(a, b);
}

/// `expected` after Encode: Encode fills the header's type and version.
template <class Pb>
Pb Stamped(Pb m, pb::MsgType type) {
  m.mutable_header()->set_type(type);
  m.mutable_header()->set_schema_version(kSchemaVersion);
  return m;
}

void CheckSameImage(const Image& a, const Image& b) {
  CHECK(a.encoding == b.encoding);
  CHECK(a.width == b.width);
  CHECK(a.height == b.height);
  CHECK(a.step == b.step);
  CHECK(a.depth_scale == b.depth_scale);
  CHECK(a.invalid_value == b.invalid_value);
  REQUIRE(a.data);
  REQUIRE(b.data);
  CHECK(*a.data == *b.data);
}

template <class Pb>
void CheckSmallRoundTrip(const Pb& msg) {
  const WireMessage wire = Encode(msg);
  CHECK(wire.blobs.empty());
  pb::Header peeked;
  std::string error;
  REQUIRE(PeekHeader(wire.header, &peeked, &error));
  CHECK(peeked.type() == TypeOf<Pb>());
  CHECK(peeked.schema_version() == kSchemaVersion);
  CHECK(peeked.seq() == msg.header().seq());
  Pb decoded;
  REQUIRE(Decode(wire, &decoded, &error));
  std::string report;
  CHECK(SameMessage(decoded, Stamped(msg, TypeOf<Pb>()), &report));
  INFO(report);
  CHECK(GetHeader(decoded).publisher() == msg.header().publisher());
}

TEST_CASE("small messages round trip with all fields", "[unit]") {
  testing::Samples s(1);
  for (int i = 0; i < 20; ++i) {
    CheckSmallRoundTrip(s.MakePoseStamped());
    CheckSmallRoundTrip(s.MakeCameraInfo());
    CheckSmallRoundTrip(s.MakePoseRequest());
    CheckSmallRoundTrip(s.MakeModelVersion());
    CheckSmallRoundTrip(s.MakeTrainerStatus());
    CheckSmallRoundTrip(s.MakeNodeStatus());
    CheckSmallRoundTrip(s.MakeRenderRequest(i % 4));
  }
}

TEST_CASE("pose values survive the round trip", "[unit]") {
  pb::PoseStamped m;
  convert::SetPose({1.5, -2.25, 3.0, 0.0, 0.0, std::sqrt(0.5), std::sqrt(0.5)},
                   m.mutable_pose());
  m.mutable_header()->set_seq(42);
  m.mutable_header()->set_capture_stamp_ns(123456789);
  m.mutable_header()->set_frame_id("world");
  pb::PoseStamped out;
  std::string error;
  REQUIRE(Decode(Encode(m), &out, &error));
  const auto v = convert::PoseVector(out.pose());
  CHECK(v[0] == 1.5);
  CHECK(v[1] == -2.25);
  CHECK(v[2] == 3.0);
  CHECK(v[5] == Approx(std::sqrt(0.5)));
  CHECK(v[6] == Approx(std::sqrt(0.5)));
  CHECK(out.header().seq() == 42);
  CHECK(out.header().capture_stamp_ns() == 123456789);
  CHECK(out.header().frame_id() == "world");
  CHECK(out.header().type() == pb::POSE);
}

TEST_CASE("RgbdFrame round trip keeps metadata and images", "[unit]") {
  testing::Samples s(2);
  for (uint32_t pad : {0u, 4u}) {
    RgbdFrame frame = s.MakeRgbdFrame(17, 9);
    frame.depth = s.MakeImage(pb::DEPTH16U, 17, 9, pad);
    frame.depth.invalid_value = 65535;
    const WireMessage wire = Encode(frame);
    REQUIRE(wire.blobs.size() == 2);
    RgbdFrame out;
    std::string error;
    REQUIRE(Decode(wire, &out, &error));
    CheckSameImage(out.rgb, frame.rgb);
    CheckSameImage(out.depth, frame.depth);
    CHECK(out.depth.step == 17 * 2 + pad);
    CHECK(out.meta.has_pose());
    CHECK(out.meta.camera_info().k(0) == frame.meta.camera_info().k(0));
    CHECK(out.meta.rgb().blob_index() != out.meta.depth().blob_index());
    CHECK(out.meta.header().seq() == frame.meta.header().seq());
  }
  SECTION("camera_info_id instead of camera info, no pose") {
    RgbdFrame frame = s.MakeRgbdFrame();
    frame.meta.set_camera_info_id("kinect");
    frame.meta.clear_pose();
    RgbdFrame out;
    std::string error;
    REQUIRE(Decode(Encode(frame), &out, &error));
    CHECK(out.meta.camera_info_id() == "kinect");
    CHECK_FALSE(out.meta.has_pose());
    CHECK_FALSE(out.meta.has_camera_info());
  }
}

TEST_CASE("View round trip keeps metadata and images", "[unit]") {
  testing::Samples s(3);
  const View view = s.MakeView(20, 10);
  View out;
  std::string error;
  REQUIRE(Decode(Encode(view), &out, &error));
  CheckSameImage(out.rgb, view.rgb);
  CheckSameImage(out.depth, view.depth);
  CHECK(out.meta.coverage() == view.meta.coverage());
  CHECK(out.meta.model_version() == view.meta.model_version());
  CHECK(out.meta.render_ms() == view.meta.render_ms());
  CHECK(out.meta.method() == "p2i");
}

TEST_CASE("RenderRequest / RenderReply round trip", "[unit]") {
  testing::Samples s(4);
  const pb::RenderRequest req = s.MakeRenderRequest(5);
  pb::RenderRequest req_out;
  std::string error;
  REQUIRE(Decode(Encode(req), &req_out, &error));
  REQUIRE(req_out.poses_size() == 5);
  for (int i = 0; i < 5; ++i) {
    const auto a = convert::PoseVector(req.poses(i));
    const auto b = convert::PoseVector(req_out.poses(i));
    for (int k = 0; k < 7; ++k) CHECK(a[k] == Approx(b[k]).margin(1e-15));
  }

  const RenderReplyMsg reply = s.MakeRenderReply(3);
  const WireMessage wire = Encode(reply);
  REQUIRE(wire.blobs.size() == 6);
  RenderReplyMsg out;
  REQUIRE(Decode(wire, &out, &error));
  REQUIRE(out.images.size() == 6);
  for (size_t i = 0; i < 6; ++i) CheckSameImage(out.images[i], reply.images[i]);
  CHECK(out.meta.views(2).coverage() == reply.meta.views(2).coverage());
  CHECK(out.meta.ok());

  SECTION("the plain protobuf reply decodes the same message and drops the images") {
    pb::RenderReply plain;
    REQUIRE(Decode(wire, &plain, &error));
    CHECK(plain.views_size() == 3);
    CHECK(plain.views(0).rgb().encoding() == pb::RGB8);
  }
  SECTION("an error reply without images") {
    pb::RenderReply failed;
    failed.set_request_id(7);
    failed.set_ok(false);
    failed.set_error("model not loaded");
    RenderReplyMsg got;
    REQUIRE(Decode(Encode(failed), &got, &error));
    CHECK(got.images.empty());
    CHECK_FALSE(got.meta.ok());
    CHECK(got.meta.error() == "model not loaded");
  }
  SECTION("metadata-only views encoded from pb::RenderReply") {
    RenderReplyMsg got;
    REQUIRE(Decode(Encode(reply.meta), &got, &error));
    CHECK(got.images.empty());
    CHECK(got.meta.views_size() == 3);
  }
}

TEST_CASE("TypeOf, TypeName and header access agree", "[unit]") {
  CHECK(TypeOf<pb::PoseStamped>() == pb::POSE);
  CHECK(TypeOf<RgbdFrame>() == pb::RGBD_FRAME);
  CHECK(TypeOf<View>() == pb::VIEW);
  CHECK(TypeOf<RenderReplyMsg>() == TypeOf<pb::RenderReply>());
  CHECK(std::string(TypeName(pb::NODE_STATUS)) == "NodeStatus");
  CHECK(std::string(TypeName(static_cast<pb::MsgType>(99))) == "Unknown");
  testing::Samples s(5);
  View view = s.MakeView();
  MutableHeader(view)->set_seq(77);
  CHECK(GetHeader(view).seq() == 77);
  CHECK(view.meta.header().seq() == 77);
}

TEST_CASE("DebugString shows fields and blobs", "[unit]") {
  testing::Samples s(6);
  RgbdFrame frame = s.MakeRgbdFrame(16, 12);
  const std::string text = DebugString(Encode(frame));
  CHECK(text.find("type: RgbdFrame") != std::string::npos);
  CHECK(text.find("camera_name: \"kinect\"") != std::string::npos);
  CHECK(text.find("<blob 0: 16 x 12 RGB8, 576 bytes>") != std::string::npos);
  CHECK(text.find("<blob 1: 16 x 12 DEPTH16U, 384 bytes>") != std::string::npos);
  CHECK(text.find("INVALID") == std::string::npos);

  WireMessage bad = Encode(frame);
  bad.blobs.pop_back();
  CHECK(DebugString(bad).find("INVALID: missing_blob") != std::string::npos);
  CHECK(DebugString(WireMessage{"\xff\xff", {}}).find("INVALID: unparsable") != std::string::npos);
}

}  // namespace
}  // namespace p2i::msgs
