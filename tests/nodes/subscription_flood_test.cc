/// @file subscription_flood_test.cc
/// @brief A real XSUB peer floods p2i_pose_source's /pose publisher with subscriptions (one
/// 1 MB frame; then 2000 random filters and one of 8 MB): the node's memory stays flat and
/// /pose keeps reaching a normal subscriber.
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <random>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/raw_subscriber.h"
#include "tests/process_util.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"

namespace {

using p2i::runtime::testing::ScopedRunDir;
using p2i::runtime::testing::WaitUntil;

// VmRSS of `pid` in MiB (/proc/PID/status), -1 if unreadable.
double RssMiB(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") {
      double kb = 0;
      in >> kb;
      return kb / 1024.0;
    }
    std::getline(in, key);
  }
  return -1;
}

// Messages /pose delivers within `ms`.
int Received(p2i::runtime::RawSubscriber* sub, int ms) {
  int n = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  while (std::chrono::steady_clock::now() < end) {
    p2i::msgs::WireMessage w;
    p2i::msgs::pb::Header h;
    if (sub->Receive(&w, &h, std::chrono::milliseconds(20))) ++n;
  }
  return n;
}

void SendSubscription(zmq::socket_t& xsub, const std::string& filter) {
  std::string frame(1, '\x01');
  frame += filter;
  xsub.send(zmq::buffer(frame), zmq::send_flags::dontwait);
}

}  // namespace

TEST_CASE("a subscription flood on a real node keeps its memory flat and /pose flowing",
          "[integration]") {
  ScopedRunDir run_dir;
  p2i::testing::Process node({p2i::testing::BinDir() + "/p2i_pose_source", "rate:=50",
                              "status_period:=0"});
  REQUIRE(node.pid() > 0);
  p2i::runtime::RawSubscriber pose("/pose", {});
  REQUIRE(WaitUntil([&] { return Received(&pose, 100) > 0; }, std::chrono::seconds(20)));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const double before = RssMiB(node.pid());
  REQUIRE(before > 0);

  const std::string endpoint = p2i::runtime::DefaultEndpoint("topic", "/pose");
  zmq::context_t ctx;
  {
    // One 1 MB subscription frame.
    zmq::socket_t xsub(ctx, zmq::socket_type::xsub);
    xsub.set(zmq::sockopt::linger, 0);
    xsub.connect(endpoint);
    SendSubscription(xsub, std::string(1 << 20, 'a'));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  {
    // 2000 short random subscriptions, 2000 up to 1000 bytes, then one of 8 MB.
    zmq::socket_t xsub(ctx, zmq::socket_type::xsub);
    xsub.set(zmq::sockopt::linger, 0);
    xsub.set(zmq::sockopt::sndhwm, 0);
    xsub.connect(endpoint);
    std::mt19937 rng(11);
    for (int i = 0; i < 2000; ++i) {  // short ones first: they fit ZMQ_MAXMSGSIZE, get refused
      std::string f(1 + rng() % 16, '\0');
      for (auto& c : f) c = static_cast<char>(rng());
      SendSubscription(xsub, f);
    }
    for (int i = 0; i < 2000; ++i) {
      std::string f(1 + rng() % 1000, '\0');
      for (auto& c : f) c = static_cast<char>(rng());
      SendSubscription(xsub, f);
    }
    SendSubscription(xsub, std::string(8 << 20, 'b'));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    // /pose still reaches a normal subscriber while the flooding peer is connected.
    const int during = Received(&pose, 500);
    CHECK(during > 0);
  }
  const double after = RssMiB(node.pid());
  WARN("pose_source RSS " << before << " MiB before, " << after << " MiB after the flood");
  CHECK(after - before < 16.0);  // a plain PUB grows by ~100 MB per MB of filter
  CHECK(Received(&pose, 300) > 0);
  // A late joiner still gets /pose (its exact-topic subscription is applied).
  p2i::runtime::RawSubscriber late("/pose", {});
  CHECK(WaitUntil([&] { return Received(&late, 100) > 0; }, std::chrono::seconds(10)));
}
