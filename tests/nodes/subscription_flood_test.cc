/// @file subscription_flood_test.cc
/// @brief A real XSUB peer floods p2i_pose_source's /pose publisher with subscriptions (one
/// 1 MB frame; then 2000 random filters and one of 8 MB): the node's memory stays flat and
/// /pose keeps reaching a normal subscriber.
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include <chrono>
#include <fstream>
#include <functional>
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

// Runs a flooding XSUB peer in a child process: `send` floods from it, `during` runs here while
// it is connected, then the child is SIGKILLed (the peer leaves). A child, because libzmq's XSUB
// keeps what it sent in a trie whose recursive destructor overflows the stack for a 1 MB
// filter: closing it in this process would crash the test, not the node.
void FloodPeer(const std::string& endpoint, const std::function<void(zmq::socket_t&)>& send,
               const std::function<void()>& during) {
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::close(ready[0]);
    zmq::context_t ctx;
    zmq::socket_t xsub(ctx, zmq::socket_type::xsub);
    xsub.set(zmq::sockopt::sndhwm, 0);
    xsub.connect(endpoint);
    send(xsub);
    const char c = 1;
    (void)!::write(ready[1], &c, 1);
    for (;;) ::pause();  // until SIGKILL
  }
  ::close(ready[1]);
  char c = 0;
  (void)!::read(ready[0], &c, 1);
  ::close(ready[0]);
  during();
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
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
  // One 1 MB subscription frame.
  FloodPeer(endpoint, [](zmq::socket_t& xsub) { SendSubscription(xsub, std::string(1 << 20, 'a')); },
            [] { std::this_thread::sleep_for(std::chrono::milliseconds(300)); });
  // 2000 short random subscriptions, then one of 8 MB (the flood).
  FloodPeer(
      endpoint,
      [](zmq::socket_t& xsub) {
        std::mt19937 rng(11);
        for (int i = 0; i < 2000; ++i) {  // they fit ZMQ_MAXMSGSIZE, get refused
          std::string f(1 + rng() % 16, '\0');
          for (auto& c : f) c = static_cast<char>(rng());
          SendSubscription(xsub, f);
        }
        SendSubscription(xsub, std::string(8 << 20, 'b'));
      },
      [&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        // /pose still reaches a normal subscriber while the flooding peer is connected.
        CHECK(Received(&pose, 500) > 0);
      });
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // a plain PUB grows as peers leave
  const double after = RssMiB(node.pid());
  WARN("pose_source RSS " << before << " MiB before, " << after << " MiB after the flood");
  CHECK(after - before < 16.0);  // a plain PUB: +90 MB for the 1 MB filter, +160..400 MB here

  // Harder: 2000 more filters of up to 1000 bytes (each fits ZMQ_MAXMSGSIZE 1024). The endpoint
  // is bound again after 64 refusals, the peer reconnects and resends them all; libzmq's XPUB
  // reads them into a queue of its own before the node refuses them, so this grows, boundedly.
  FloodPeer(
      endpoint,
      [](zmq::socket_t& xsub) {
        std::mt19937 rng(12);
        for (int i = 0; i < 2000; ++i) {
          std::string f(1 + rng() % 1000, '\0');
          for (auto& c : f) c = static_cast<char>(rng());
          SendSubscription(xsub, f);
        }
      },
      [&] { std::this_thread::sleep_for(std::chrono::milliseconds(1000)); });
  const double after_long = RssMiB(node.pid());
  WARN("pose_source RSS " << after_long << " MiB after 2000 filters of up to 1000 bytes");
  CHECK(after_long - before < 64.0);
  CHECK(Received(&pose, 300) > 0);
  // A late joiner still gets /pose (its exact-topic subscription is applied).
  p2i::runtime::RawSubscriber late("/pose", {});
  CHECK(WaitUntil([&] { return Received(&late, 100) > 0; }, std::chrono::seconds(10)));
}
