/// @file raw_service_test.cc
/// @brief ROUTER/DEALER services: concurrency, Lazy Pirate retries, ZMQ_MAXMSGSIZE, ipc + tcp.
#include <catch2/catch.hpp>

#include <atomic>
#include <memory>
#include <thread>

#include "nodes/runtime/raw_service.h"
#include "nodes/runtime/shutdown.h"
#include "tests/runtime/test_util.h"

using namespace p2i::runtime;
using p2i::msgs::WireMessage;

namespace {

/// Runs a RawServiceServer on its own thread (its socket's owner) that echoes the header with
/// a "reply:" prefix; can be stopped and restarted.
class EchoServer {
 public:
  EchoServer(const std::string& name, ServiceServerOptions options = {})
      : name_(name), options_(options) {}
  ~EchoServer() { StopServer(); }
  void StartServer() {
    stop_ = false;
    std::atomic<bool> ready{false};
    thread_ = std::thread([this, &ready] {
      RawServiceServer server(name_, "Echo", "/test", options_,
                              [this](const WireMessage& req, uint64_t, WireMessage* rep,
                                     std::string* error) {
                                if (req.header == "fail") {
                                  *error = "asked to fail";
                                  return false;
                                }
                                rep->header = "reply:" + req.header;
                                rep->blobs = req.blobs;
                                ++handled_;
                                return true;
                              });
      endpoint_ = server.Endpoint();
      ready = true;
      while (!stop_) {
        zmq::pollitem_t item{server.Socket().handle(), 0, ZMQ_POLLIN, 0};
        zmq::poll(&item, 1, std::chrono::milliseconds(10));
        server.Drain();
      }
    });
    while (!ready) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  void StopServer() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::string Endpoint() const { return endpoint_; }
  int Handled() const { return handled_; }

 private:
  std::string name_;
  ServiceServerOptions options_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> handled_{0};
  std::string endpoint_;
};

WireMessage Request(const std::string& text) {
  WireMessage m;
  m.header = text;
  return m;
}

}  // namespace

TEST_CASE("Service: many concurrent clients each get their own replies (ipc and tcp)",
          "[integration]") {
  Shutdown::ResetForTesting();
  testing::ScopedRunDir run_dir;
  const bool tcp = GENERATE(false, true);
  ServiceServerOptions so;
  if (tcp) so.endpoint = "tcp://127.0.0.1:*";
  EchoServer server("/echo", so);
  server.StartServer();
  if (tcp) CHECK(server.Endpoint().rfind("tcp://127.0.0.1:", 0) == 0);
  else CHECK(server.Endpoint().rfind("ipc://" + run_dir.Path(), 0) == 0);

  constexpr int kClients = 8, kCalls = 50;
  std::atomic<int> good{0}, bad{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < kClients; ++c) {
    clients.emplace_back([&, c] {
      ServiceClientOptions co;
      co.endpoint = server.Endpoint();
      RawServiceClient client("/echo", co);
      for (int i = 0; i < kCalls; ++i) {
        const std::string text = std::to_string(c) + "/" + std::to_string(i);
        WireMessage reply;
        std::string error;
        if (client.Call(Request(text), &reply, &error) && reply.header == "reply:" + text) ++good;
        else ++bad;
      }
    });
  }
  for (auto& t : clients) t.join();
  CHECK(good == kClients * kCalls);
  CHECK(bad == 0);
  CHECK(server.Handled() == kClients * kCalls);
}

TEST_CASE("Service: a handler error reaches the client as an error", "[integration]") {
  Shutdown::ResetForTesting();
  testing::ScopedRunDir run_dir;
  EchoServer server("/echo");
  server.StartServer();
  RawServiceClient client("/echo", {});
  WireMessage reply;
  std::string error;
  CHECK_FALSE(client.Call(Request("fail"), &reply, &error));
  CHECK(error.find("asked to fail") != std::string::npos);
  CHECK(client.Call(Request("ok"), &reply, &error));
  CHECK(reply.header == "reply:ok");
}

TEST_CASE("Service client retries until a late server starts, and fails when none does",
          "[integration]") {
  Shutdown::ResetForTesting();
  testing::ScopedRunDir run_dir;
  ServiceClientOptions co;
  co.timeout = std::chrono::milliseconds(200);
  co.retries = 10;
  RawServiceClient client("/late", co);
  EchoServer server("/late");
  std::thread starter([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    server.StartServer();
  });
  WireMessage reply;
  std::string error;
  const bool ok = client.Call(Request("hello"), &reply, &error);
  starter.join();
  CHECK(ok);
  CHECK(reply.header == "reply:hello");
  CHECK(client.Stats().timeouts.load() >= 1);  // it really had to retry

  server.StopServer();  // the server dies ...
  co.retries = 1;
  RawServiceClient impatient("/late", co);
  CHECK_FALSE(impatient.Call(Request("anyone?"), &reply, &error));
  CHECK(error.find("2 attempt(s)") != std::string::npos);

  std::thread restarter([&] {  // ... and comes back
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    server.StartServer();
  });
  CHECK(client.Call(Request("again"), &reply, &error));
  restarter.join();
  CHECK(reply.header == "reply:again");
}

TEST_CASE("Service: ZMQ_MAXMSGSIZE rejects an oversized request, normal ones still work",
          "[integration]") {
  Shutdown::ResetForTesting();
  testing::ScopedRunDir run_dir;
  ServiceServerOptions so;
  so.max_message_bytes = 1 << 16;
  EchoServer server("/small", so);
  server.StartServer();
  ServiceClientOptions co;
  co.timeout = std::chrono::milliseconds(300);
  co.retries = 1;
  RawServiceClient client("/small", co);
  WireMessage big = Request("big");
  big.blobs.push_back(std::make_shared<const p2i::msgs::Bytes>(1 << 17, 7));
  WireMessage reply;
  std::string error;
  CHECK_FALSE(client.Call(big, &reply, &error));
  CHECK(server.Handled() == 0);
  WireMessage fits = Request("fits");
  fits.blobs.push_back(std::make_shared<const p2i::msgs::Bytes>(1 << 15, 7));
  REQUIRE(client.Call(fits, &reply, &error));
  CHECK(reply.header == "reply:fits");
  REQUIRE(reply.blobs.size() == 1);
  CHECK(reply.blobs[0]->size() == (1u << 15));
  CHECK(server.Handled() == 1);
}
