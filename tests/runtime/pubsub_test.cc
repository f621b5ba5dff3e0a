/// @file pubsub_test.cc
/// @brief PUB/SUB transport: exact topics, drop counting, latest-only, malformed input, ipc+tcp.
#include <catch2/catch.hpp>

#include <thread>

#include "msgs/codec.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/shutdown.h"
#include "nodes/runtime/wire_io.h"
#include "nodes/runtime/zmq_context.h"
#include "tests/runtime/test_util.h"

using namespace p2i;
using namespace p2i::runtime;
using p2i::runtime::testing::ScopedRunDir;
using p2i::runtime::testing::WaitUntil;

namespace {

msgs::pb::PoseStamped MakePose(uint64_t seq, const std::string& publisher, double x = 0) {
  msgs::pb::PoseStamped m;
  m.mutable_header()->set_seq(seq);
  m.mutable_header()->set_publisher(publisher);
  m.mutable_pose()->mutable_position()->set_x(x);
  m.mutable_pose()->mutable_orientation()->set_w(1.0);
  return m;
}

/// A bare PUB socket that lets a test send any frames at all.
class RawPub {
 public:
  explicit RawPub(const std::string& endpoint) : socket_(ZmqContext(), zmq::socket_type::pub) {
    socket_.set(zmq::sockopt::linger, 0);
    socket_.bind(endpoint);
    endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
  }
  void SendFrames(const std::vector<std::string>& frames) {
    for (size_t i = 0; i < frames.size(); ++i) {
      socket_.send(zmq::buffer(frames[i]),
                   i + 1 < frames.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
    }
  }
  void Send(const std::string& topic, const msgs::WireMessage& m) {
    socket_.send(zmq::buffer(topic + std::string(1, '\0')), zmq::send_flags::sndmore);
    SendWire(socket_, m);
  }
  const std::string& Endpoint() const { return endpoint_; }

 private:
  zmq::socket_t socket_;
  std::string endpoint_;
};

/// Publishes `probe` until the subscriber has received something (ZeroMQ's slow joiner).
void Handshake(const std::function<void()>& send_probe, RawSubscriber& sub,
               std::vector<uint64_t>* seqs = nullptr) {
  for (int i = 0; i < 400; ++i) {
    send_probe();
    bool got = false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    sub.Drain([&](msgs::WireMessage&&, const msgs::pb::Header& h) {
      got = true;
      if (seqs) seqs->push_back(h.seq());
      return true;
    });
    if (got) return;
  }
  FAIL("subscriber never connected");
}

}  // namespace

TEST_CASE("PubSub: 'pose' does not receive 'pose_est' or a topic frame with a suffix", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  RawPub pub("ipc://" + run_dir.Path() + "/shared.ipc");
  SubscriberOptions so;
  so.endpoints = {pub.Endpoint()};
  RawSubscriber sub("/pose", so);
  uint64_t seq = 0;
  Handshake([&] { pub.Send("/pose", msgs::Encode(MakePose(++seq, "/p"))); }, sub);
  const auto received_before = sub.Stats().received.load();

  pub.Send("/pose_est", msgs::Encode(MakePose(++seq, "/p", 1)));
  // Prefix "/pose\0" matches ZeroMQ's filter; only the equality check stops this one.
  pub.SendFrames({std::string("/pose\0x", 7), msgs::Encode(MakePose(++seq, "/p", 2)).header});
  pub.Send("/pose", msgs::Encode(MakePose(++seq, "/p", 3)));
  std::vector<double> xs;
  WaitUntil([&] {
    sub.Drain([&](msgs::WireMessage&& m, const msgs::pb::Header&) {
      msgs::pb::PoseStamped p;
      std::string e;
      REQUIRE(msgs::Decode(m, &p, &e));
      xs.push_back(p.pose().position().x());
      return true;
    });
    return !xs.empty();
  });
  REQUIRE(xs.size() == 1);
  CHECK(xs[0] == 3.0);
  CHECK(sub.Stats().received.load() == received_before + 1);
  CHECK(sub.Stats().malformed.load() == 1);  // the suffixed topic frame
}

TEST_CASE("PubSub: sequence gaps are counted as drops per publisher", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  RawPub pub("ipc://" + run_dir.Path() + "/gap.ipc");
  SubscriberOptions so;
  so.endpoints = {pub.Endpoint()};
  RawSubscriber sub("/t", so);
  std::vector<uint64_t> seqs;
  uint64_t probe = 100;
  Handshake([&] { pub.Send("/t", msgs::Encode(MakePose(++probe, "/probe"))); }, sub, &seqs);
  for (uint64_t s : {1, 2, 5, 6}) pub.Send("/t", msgs::Encode(MakePose(s, "/a")));
  for (uint64_t s : {10, 11, 11, 12}) pub.Send("/t", msgs::Encode(MakePose(s, "/b")));
  seqs.clear();
  WaitUntil([&] {
    sub.Drain([&](msgs::WireMessage&&, const msgs::pb::Header& h) {
      seqs.push_back(h.seq());
      return true;
    });
    return seqs.size() >= 7;
  });
  CHECK(seqs == std::vector<uint64_t>{1, 2, 5, 6, 10, 11, 12});
  CHECK(sub.Stats().dropped.load() == 2);     // 3 and 4 of /a; /b has none
  CHECK(sub.Stats().duplicates.load() == 1);  // the second 11 (latched re-publication)
}

TEST_CASE("PubSub: latest-only delivers the newest and skips the backlog", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  auto pub = std::make_shared<RawPublisher>("/view", "PoseStamped", "/n", PublisherOptions{});
  Publisher<msgs::pb::PoseStamped> typed(pub, "/n");
  SubscriberOptions so;
  so.latest_only = true;
  RawSubscriber sub("/view", so);
  Handshake([&] { typed.Publish(MakePose(0, "")); }, sub);
  for (int i = 1; i <= 50; ++i) typed.Publish(MakePose(0, "", i));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the backlog arrive
  std::vector<double> delivered;
  WaitUntil([&] {
    sub.Drain([&](msgs::WireMessage&& m, const msgs::pb::Header&) {
      msgs::pb::PoseStamped p;
      std::string e;
      REQUIRE(msgs::Decode(m, &p, &e));
      delivered.push_back(p.pose().position().x());
      return true;
    });
    return !delivered.empty() && delivered.back() == 50.0;
  });
  REQUIRE_FALSE(delivered.empty());
  CHECK(delivered.back() == 50.0);
  CHECK(delivered.size() < 10);  // without latest-only it would be all 50
  CHECK(sub.Stats().skipped.load() > 0);
}

TEST_CASE("PubSub: malformed messages are counted and dropped, never a crash", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  RawPub pub("ipc://" + run_dir.Path() + "/bad.ipc");
  SubscriberOptions so;
  so.endpoints = {pub.Endpoint()};
  RawSubscriber sub("/rgbd", so);
  uint64_t seq = 0;
  Handshake([&] { pub.Send("/rgbd", msgs::Encode(MakePose(++seq, "/probe"))); }, sub);

  pub.SendFrames({std::string("/rgbd\0", 6)});                          // no header frame
  pub.SendFrames({std::string("/rgbd\0", 6), "\xff\xff\xff garbage"});  // unparsable header
  // An RgbdFrame whose depth blob is truncated: the transport accepts it, Decode must not.
  msgs::RgbdFrame f;
  f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, 4, 2);
  f.depth = msgs::Image::Allocate(msgs::pb::DEPTH16U, 4, 2);
  f.depth.depth_scale = 0.001;
  f.meta.set_camera_info_id("cam");
  f.meta.mutable_header()->set_seq(++seq);
  f.meta.mutable_header()->set_publisher("/probe");
  auto wire = msgs::Encode(f);
  REQUIRE(wire.blobs.size() == 2);
  wire.blobs[1] = std::make_shared<const msgs::Bytes>(3, 0);
  pub.Send("/rgbd", wire);
  pub.Send("/rgbd", msgs::Encode(MakePose(++seq, "/probe", 7)));  // a good one after all that

  int decoded = 0, rejected = 0;
  double last_x = -1;
  WaitUntil([&] {
    sub.Drain([&](msgs::WireMessage&& m, const msgs::pb::Header& h) {
      std::string e;
      if (h.type() == msgs::pb::RGBD_FRAME) {
        msgs::RgbdFrame out;
        if (msgs::Decode(m, &out, &e)) ++decoded; else ++rejected;
        return false;  // tells the subscriber it was unusable
      }
      msgs::pb::PoseStamped p;
      REQUIRE(msgs::Decode(m, &p, &e));
      last_x = p.pose().position().x();
      return true;
    });
    return last_x == 7.0;
  });
  CHECK(last_x == 7.0);
  CHECK(decoded == 0);
  CHECK(rejected == 1);
  CHECK(sub.Stats().malformed.load() == 3);
}

TEST_CASE("PubSub: RGB-D frames arrive intact over ipc and tcp", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  const std::string endpoint = GENERATE(std::string(""), std::string("tcp://127.0.0.1:*"));
  PublisherOptions po;
  po.endpoint = endpoint;
  auto raw = std::make_shared<RawPublisher>("/cam/rgbd", "RgbdFrame", "/cam", po);
  if (endpoint.empty()) CHECK(raw->Endpoint() == DefaultEndpoint("topic", "/cam/rgbd"));
  else CHECK(raw->Endpoint().rfind("tcp://127.0.0.1:", 0) == 0);
  Publisher<msgs::RgbdFrame> pub(raw, "/cam");
  SubscriberOptions so;
  so.endpoints = {raw->Endpoint()};
  RawSubscriber sub("/cam/rgbd", so);
  msgs::RgbdFrame f;
  f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, 64, 48);
  for (size_t i = 0; i < f.rgb.data->size(); ++i) f.rgb.MutableData()[i] = uint8_t(i * 13);
  f.depth = msgs::Image::Allocate(msgs::pb::DEPTH16U, 64, 48);
  for (size_t i = 0; i < f.depth.data->size(); ++i) f.depth.MutableData()[i] = uint8_t(i * 5);
  f.depth.depth_scale = 0.001;
  f.meta.set_camera_info_id("cam");
  msgs::RgbdFrame got;
  bool ok = false;
  for (int i = 0; i < 400 && !ok; ++i) {
    pub.Publish(f);
    msgs::WireMessage m;
    msgs::pb::Header h;
    if (sub.Receive(&m, &h, std::chrono::milliseconds(10))) {
      std::string e;
      REQUIRE(msgs::Decode(m, &got, &e));
      CHECK(h.publisher() == "/cam");
      CHECK(h.seq() >= 1);
      ok = true;
    }
  }
  REQUIRE(ok);
  CHECK(*got.rgb.data == *f.rgb.data);
  CHECK(*got.depth.data == *f.depth.data);
  CHECK(got.depth.depth_scale == 0.001);
}

TEST_CASE("PubSub: a second publisher cannot take over a bound ipc endpoint", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  RawPublisher first("/dup", "PoseStamped", "/a", PublisherOptions{});
  try {
    RawPublisher second("/dup", "PoseStamped", "/b", PublisherOptions{});
    FAIL("expected the second bind to be refused");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("node /a") != std::string::npos);
  }
}
