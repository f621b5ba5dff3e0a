/// @file inline_blobs_test.cc
/// @brief Recorded messages are self-contained protobufs (pixels inline) that decode with the
/// embedded schema and convert back to the same WireMessage; Foxglove conversion of frames.
#include <catch2/catch.hpp>

#include <cstring>

#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>

#include "convert/pose.h"
#include "msgs/codec.h"
#include "msgs/foxglove.pb.h"
#include "recording/foxglove_convert.h"
#include "recording/inline_blobs.h"
#include "recording/proto_schema.h"
#include "tests/recording/recording_test_util.h"

using namespace p2i;
using namespace p2i::recording;
namespace gp = google::protobuf;

TEST_CASE("Inline blobs: RgbdFrame -> recorded bytes -> the same frame", "[unit]") {
  const msgs::RgbdFrame f = testing::SampleFrame(16, 12, 3);
  const msgs::WireMessage wire = msgs::Encode(f);
  std::string error;
  auto rec = InlinedMessage::Make(msgs::pb::RgbdFrame::descriptor(), wire, &error);
  REQUIRE(rec);
  const std::string bytes = rec->ToString();
  CHECK(bytes.size() > msgs::WireSize(wire));  // pixels + a few tag bytes
  CHECK(bytes.compare(0, wire.header.size(), wire.header) == 0);  // header frame unchanged

  // A generic protobuf reader with only the embedded FileDescriptorSet sees the pixels.
  gp::FileDescriptorSet set;
  REQUIRE(set.ParseFromString(RecordingSchema(msgs::pb::RgbdFrame::descriptor())));
  gp::DescriptorPool pool;
  for (const auto& file : set.file()) REQUIRE(pool.BuildFile(file));
  const gp::Descriptor* d = pool.FindMessageTypeByName("p2i.msgs.pb.RgbdFrame");
  REQUIRE(d);
  gp::DynamicMessageFactory factory(&pool);
  std::unique_ptr<gp::Message> dyn(factory.GetPrototype(d)->New());
  REQUIRE(dyn->ParseFromString(bytes));
  const gp::Message& rgb = dyn->GetReflection()->GetMessage(*dyn, d->FindFieldByName("rgb"));
  const std::string px = rgb.GetReflection()->GetString(rgb, rgb.GetDescriptor()->FindFieldByName("data"));
  REQUIRE(px.size() == f.rgb.data->size());
  CHECK(std::memcmp(px.data(), f.rgb.data->data(), px.size()) == 0);

  // Back to the wire: decodes as the original frame.
  msgs::WireMessage back;
  REQUIRE(ExtractBlobs("p2i.msgs.pb.RgbdFrame", reinterpret_cast<const uint8_t*>(bytes.data()),
                       bytes.size(), &back, &error));
  msgs::RgbdFrame g;
  REQUIRE(msgs::Decode(back, &g, &error));
  CHECK(*g.rgb.data == *f.rgb.data);
  CHECK(*g.depth.data == *f.depth.data);
  CHECK(g.meta.header().seq() == f.meta.header().seq());
  CHECK(g.meta.pose().position().x() == Approx(0.3));
  CHECK(g.meta.camera_info().width() == 16);
  CHECK(back.header.size() < 1000);  // the wire header frame carries no pixels

  // A blob-less type passes through unchanged.
  msgs::pb::PoseStamped p;
  convert::SetPose({1, 2, 3, 0, 0, 0, 1}, p.mutable_pose());
  const auto pw = msgs::Encode(p);
  auto pr = InlinedMessage::Make(msgs::pb::PoseStamped::descriptor(), pw, &error);
  REQUIRE(pr);
  CHECK(pr->ToString() == pw.header);
}

TEST_CASE("Inline blobs: RenderReply with images in repeated views round-trips", "[unit]") {
  msgs::RenderReplyMsg r;
  r.meta.set_ok(true);
  for (int i = 0; i < 2; ++i) {
    auto* v = r.meta.add_views();
    convert::SetPose({0.1 * i, 0, 0, 0, 0, 0, 1}, v->mutable_pose());
    msgs::Image rgb = msgs::Image::Allocate(msgs::pb::RGB8, 4, 3);
    rgb.MutableData()[0] = static_cast<uint8_t>(10 + i);
    r.images.push_back(rgb);
    r.images.push_back(msgs::Image::Allocate(msgs::pb::DEPTH32F, 4, 3));
  }
  const auto wire = msgs::Encode(r);
  std::string error;
  auto rec = InlinedMessage::Make(msgs::pb::RenderReply::descriptor(), wire, &error);
  REQUIRE(rec);
  const std::string bytes = rec->ToString();
  msgs::WireMessage back;
  REQUIRE(ExtractBlobs("p2i.msgs.pb.RenderReply", reinterpret_cast<const uint8_t*>(bytes.data()),
                       bytes.size(), &back, &error));
  msgs::RenderReplyMsg g;
  REQUIRE(msgs::Decode(back, &g, &error));
  REQUIRE(g.images.size() == 4);
  CHECK((*g.images[2].data)[0] == 11);
  // Garbage is an error, not a crash.
  CHECK_FALSE(ExtractBlobs("p2i.msgs.pb.RgbdFrame", reinterpret_cast<const uint8_t*>("\xff\xff"),
                           2, &back, &error));
  CHECK_FALSE(ExtractBlobs("no.Such", nullptr, 0, &back, &error));
}

TEST_CASE("Foxglove: an RgbdFrame gives RawImage rgb/depth, calibration and a transform",
          "[unit]") {
  const msgs::RgbdFrame f = testing::SampleFrame(8, 6, 1);
  const auto out = ToFoxglove("/camera/rgbd", msgs::Encode(f));
  std::map<std::string, const FoxgloveMessage*> by_topic;
  for (const auto& m : out) by_topic[m.topic] = &m;
  REQUIRE(by_topic.count("/camera/rgbd/foxglove/rgb"));
  REQUIRE(by_topic.count("/camera/rgbd/foxglove/depth"));
  REQUIRE(by_topic.count("/camera/rgbd/foxglove/calibration"));
  REQUIRE(by_topic.count("/camera/rgbd/foxglove/tf"));
  foxglove::RawImage rgb, depth;
  REQUIRE(rgb.ParseFromString(by_topic["/camera/rgbd/foxglove/rgb"]->data));
  CHECK(by_topic["/camera/rgbd/foxglove/rgb"]->schema->full_name() == "foxglove.RawImage");
  CHECK(rgb.encoding() == "rgb8");
  CHECK(rgb.width() == 8);
  CHECK(rgb.frame_id() == "camera");
  CHECK(rgb.timestamp().seconds() == f.meta.header().capture_stamp_ns() / 1000000000);
  CHECK(rgb.data() == std::string(f.rgb.data->begin(), f.rgb.data->end()));
  REQUIRE(depth.ParseFromString(by_topic["/camera/rgbd/foxglove/depth"]->data));
  CHECK(depth.encoding() == "16UC1");
  uint16_t mm0 = 0;
  std::memcpy(&mm0, depth.data().data(), 2);
  CHECK(mm0 == 1500);  // 0.5 + 1 (seed) metres
  foxglove::CameraCalibration cal;
  REQUIRE(cal.ParseFromString(by_topic["/camera/rgbd/foxglove/calibration"]->data));
  CHECK(cal.k_size() == 9);
  CHECK(cal.p_size() == 12);
  foxglove::FrameTransform tf;
  REQUIRE(tf.ParseFromString(by_topic["/camera/rgbd/foxglove/tf"]->data));
  CHECK(tf.parent_frame_id() == "world");
  CHECK(tf.child_frame_id() == "camera");
  CHECK(tf.translation().x() == Approx(0.1));
  // Types without a counterpart, and garbage, give nothing.
  msgs::pb::NodeStatus s;
  CHECK(ToFoxglove("/x/status", msgs::Encode(s)).empty());
  msgs::WireMessage junk;
  junk.header = "junk";
  CHECK(ToFoxglove("/x", junk).empty());
}
