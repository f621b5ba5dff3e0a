/// @file curve_test.cc
/// @brief CURVE + ZAP on real tcp sockets on 127.0.0.1: the authorised path, and a plain client,
/// an unlisted key, a wrong server key and garbage handshakes refused, counted, logged and never
/// given data; key files and the key directory's errors; the 0700 run directory.
#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>
#include <vector>

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include "msgs/codec.h"
#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_service.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/zmq_context.h"
#include "tests/runtime/test_util.h"

using namespace p2i;
using namespace p2i::runtime;
using p2i::runtime::testing::ScopedRunDir;
using p2i::runtime::testing::WaitUntil;

namespace {

struct Keys {
  CurveKeyPair server = GenerateCurveKeyPair();   // this process as server and listed client
  CurveKeyPair stranger = GenerateCurveKeyPair(); // not listed
};

/// Turns CURVE on for this process for the test's lifetime (self = server, listed as client).
class ScopedCurve {
 public:
  explicit ScopedCurve(const Keys& k) {
    CurveConfig c;
    c.enabled = true;
    c.dir = "/test-keys";
    c.self = k.server;
    c.authorized = {k.server.public_z85};
    c.servers = {{"127.0.0.1", k.server.public_z85}};
    CurveSecurity::Configure(c);
  }
  ~ScopedCurve() { CurveSecurity::Configure(CurveConfig{}); }
};

/// Captures the CURVE warnings.
class ScopedLogCapture {
 public:
  ScopedLogCapture() {
    sink_ = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(1000);
    CurveSecurity::SetLogger(std::make_shared<spdlog::logger>("capture", sink_));
  }
  ~ScopedLogCapture() { CurveSecurity::SetLogger(nullptr); }
  std::string Text() const {
    std::string all;
    for (const auto& line : sink_->last_formatted()) all += line;
    return all;
  }

 private:
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink_;
};

msgs::pb::PoseStamped Pose(double x) {
  msgs::pb::PoseStamped m;
  m.mutable_pose()->mutable_position()->set_x(x);
  m.mutable_pose()->mutable_orientation()->set_w(1.0);
  return m;
}

/// A bare SUB with whatever security the test wants; counts every message it gets.
struct ProbeSub {
  zmq::socket_t socket{ZmqContext(), zmq::socket_type::sub};
  int received = 0;
  ProbeSub() {
    socket.set(zmq::sockopt::linger, 0);
    socket.set(zmq::sockopt::subscribe, "");
  }
  void Poll() {
    zmq::message_t m;
    while (socket.recv(m, zmq::recv_flags::dontwait)) ++received;
  }
};

/// Publishes until `done` (or 5 s), polling `probe` between messages.
bool PublishUntil(Publisher<msgs::pb::PoseStamped>& pub, ProbeSub* probe,
                  const std::function<bool()>& done) {
  for (int i = 0; i < 1000; ++i) {
    pub.Publish(Pose(i));
    if (probe) probe->Poll();
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

uint64_t RefusedHandshakes() { return CurveSecurity::Stats().refused_handshake.load(); }
uint64_t RefusedKeys() { return CurveSecurity::Stats().refused_key.load(); }

int PortOf(const std::string& endpoint) {
  return std::stoi(endpoint.substr(endpoint.rfind(':') + 1));
}

/// Opens a raw TCP connection to 127.0.0.1:port and writes `bytes`.
void SendRawTcp(int port, const std::string& bytes) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0);
  (void)!::write(fd, bytes.data(), bytes.size());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ::close(fd);
}

}  // namespace

TEST_CASE("CURVE: key files round-trip, bad keys and key directories are named", "[unit]") {
  REQUIRE(CurveAvailable());
  ScopedRunDir dir;
  const CurveKeyPair k = GenerateCurveKeyPair();
  CHECK(IsZ85Key(k.public_z85));
  CHECK(IsZ85Key(k.secret_z85));
  CHECK_FALSE(IsZ85Key("short"));
  const std::string path = dir.Path() + "/a.key";
  WriteKeyFile(path, k, true);
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0600);
  const CurveKeyPair back = ReadKeyFile(path);
  CHECK(back.public_z85 == k.public_z85);
  CHECK(back.secret_z85 == k.secret_z85);

  // A public key that does not belong to the secret one.
  std::ofstream(dir.Path() + "/mixed.key")
      << "public " << GenerateCurveKeyPair().public_z85 << "\nsecret " << k.secret_z85 << "\n";
  CHECK_THROWS_WITH(ReadKeyFile(dir.Path() + "/mixed.key"),
                    Catch::Contains("does not belong to the secret key"));
  std::ofstream(dir.Path() + "/bad.key") << "public not-a-key\n";
  CHECK_THROWS_WITH(ReadKeyFile(dir.Path() + "/bad.key"), Catch::Contains("bad.key:1"));

  // The key directory: missing self.key, open permissions, bad authorized_keys line.
  const std::string keys = dir.Path() + "/keys";
  ::mkdir(keys.c_str(), 0700);
  CHECK_THROWS_WITH(CurveConfig::Load(keys), Catch::Contains("p2i keygen --init"));
  WriteKeyFile(keys + "/self.key", k, true);
  ::chmod((keys + "/self.key").c_str(), 0644);
  CHECK_THROWS_WITH(CurveConfig::Load(keys), Catch::Contains("chmod 600"));
  ::chmod((keys + "/self.key").c_str(), 0600);
  CHECK_THROWS_WITH(CurveConfig::Load(keys), Catch::Contains("no authorized_keys"));
  std::ofstream(keys + "/authorized_keys") << "# comment\n" << k.public_z85 << " me\nxyz\n";
  std::ofstream(keys + "/servers") << "* " << k.public_z85 << "\n";
  CHECK_THROWS_WITH(CurveConfig::Load(keys), Catch::Contains("authorized_keys:3"));
  std::ofstream(keys + "/authorized_keys") << "# comment\n" << k.public_z85 << " me\n";
  const CurveConfig c = CurveConfig::Load(keys);
  CHECK(c.enabled);
  CHECK(c.authorized.count(k.public_z85) == 1);
  CHECK(c.ServerKeyFor("tcp://10.0.0.1:5555") == k.public_z85);
  CurveConfig no_default = c;
  no_default.servers = {{"127.0.0.1", k.public_z85}};
  CHECK_THROWS_WITH(no_default.ServerKeyFor("tcp://10.0.0.1:5555"),
                    Catch::Contains("add a line '10.0.0.1 PUBLICKEY'"));
}

TEST_CASE("CURVE: ipc endpoints live in a run directory only the user can open", "[unit]") {
  ScopedRunDir dir;
  ::chmod(dir.Path().c_str(), 0755);
  RunDir();
  struct stat st {};
  REQUIRE(::stat(dir.Path().c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0700);
}

TEST_CASE("CURVE: an authorised subscriber gets the data, a plain one is refused", "[integration]") {
  ScopedRunDir dir;
  Keys keys;
  ScopedCurve curve(keys);
  ScopedLogCapture log;
  PublisherOptions po;
  po.endpoint = "tcp://127.0.0.1:*";
  Publisher<msgs::pb::PoseStamped> pub(
      std::make_shared<RawPublisher>("/secure", "PoseStamped", "/test", po), "/test");
  SubscriberOptions so;
  so.endpoints = {pub.Raw().Endpoint()};
  RawSubscriber good("/secure", so);  // CURVE client with the listed key (process config)
  ProbeSub plain;                      // no CURVE at all
  plain.socket.connect(pub.Raw().Endpoint());
  const uint64_t refused0 = RefusedHandshakes();
  int good_received = 0;
  REQUIRE(PublishUntil(pub, &plain, [&] {
    msgs::WireMessage m;
    msgs::pb::Header h;
    while (good.Receive(&m, &h, std::chrono::milliseconds(0))) ++good_received;
    return good_received > 0 && RefusedHandshakes() > refused0;
  }));
  for (int i = 0; i < 20; ++i) {
    pub.Publish(Pose(i));
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  plain.Poll();
  CHECK(plain.received == 0);
  CHECK(CurveSecurity::Stats().accepted.load() > 0);
  // The refusal counted above need not be logged as a plain client: when the plain end reads the
  // server's CURVE greeting first, it hangs up (and, a protocol error ending its session in
  // libzmq, never reconnects), so the server sees an abandoned handshake with no detail. Fresh
  // plain clients are tried until one is refused with the mechanism mismatch named; none of them
  // ever gets a message.
  std::vector<std::unique_ptr<ProbeSub>> probes;
  bool named = false;
  for (int attempt = 0; attempt < 40 && !named; ++attempt) {
    probes.push_back(std::make_unique<ProbeSub>());
    probes.back()->socket.connect(pub.Raw().Endpoint());
    const uint64_t before = RefusedHandshakes();
    PublishUntil(pub, probes.back().get(), [&] { return RefusedHandshakes() > before; });
    named = WaitUntil([&] { return log.Text().find("plain client") != std::string::npos; },
                      std::chrono::milliseconds(200));
  }
  INFO(log.Text());
  CHECK(named);
  for (auto& p : probes) {
    p->Poll();
    CHECK(p->received == 0);
  }
}

TEST_CASE("CURVE: a client with an unlisted key is refused by ZAP, counted, logged", "[integration]") {
  ScopedRunDir dir;
  Keys keys;
  ScopedCurve curve(keys);
  ScopedLogCapture log;
  PublisherOptions po;
  po.endpoint = "tcp://127.0.0.1:*";
  Publisher<msgs::pb::PoseStamped> pub(
      std::make_shared<RawPublisher>("/secure", "PoseStamped", "/test", po), "/test");
  // A client whose handshake is cut short (a loaded machine) does not come back (libzmq ends its
  // session): fresh strangers are tried until ZAP has refused one.
  std::vector<std::unique_ptr<ProbeSub>> strangers;
  const uint64_t refused0 = RefusedKeys();
  bool refused = false;
  for (int attempt = 0; attempt < 5 && !refused; ++attempt) {
    strangers.push_back(std::make_unique<ProbeSub>());
    ProbeSub& stranger = *strangers.back();
    stranger.socket.set(zmq::sockopt::curve_serverkey, keys.server.public_z85);
    stranger.socket.set(zmq::sockopt::curve_publickey, keys.stranger.public_z85);
    stranger.socket.set(zmq::sockopt::curve_secretkey, keys.stranger.secret_z85);
    stranger.socket.connect(pub.Raw().Endpoint());
    refused = PublishUntil(pub, &stranger, [&] { return RefusedKeys() > refused0; });
  }
  INFO(log.Text());
  REQUIRE(refused);
  for (int i = 0; i < 20; ++i) pub.Publish(Pose(i));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (auto& stranger : strangers) {
    stranger->Poll();
    CHECK(stranger->received == 0);
  }
  CHECK(WaitUntil([&] {
    return log.Text().find("unlisted key " + keys.stranger.public_z85) != std::string::npos;
  }));
}

TEST_CASE("CURVE: a client with a wrong server key and garbage handshakes are refused", "[integration]") {
  ScopedRunDir dir;
  Keys keys;
  ScopedCurve curve(keys);
  ScopedLogCapture log;
  PublisherOptions po;
  po.endpoint = "tcp://127.0.0.1:*";
  Publisher<msgs::pb::PoseStamped> pub(
      std::make_shared<RawPublisher>("/secure", "PoseStamped", "/test", po), "/test");
  ProbeSub wrong;  // listed client key, but it believes in another server key
  wrong.socket.set(zmq::sockopt::curve_serverkey, keys.stranger.public_z85);
  wrong.socket.set(zmq::sockopt::curve_publickey, keys.server.public_z85);
  wrong.socket.set(zmq::sockopt::curve_secretkey, keys.server.secret_z85);
  wrong.socket.connect(pub.Raw().Endpoint());
  uint64_t refused0 = RefusedHandshakes();
  REQUIRE(PublishUntil(pub, &wrong, [&] { return RefusedHandshakes() > refused0; }));
  wrong.Poll();
  CHECK(wrong.received == 0);

  // A ZMTP 3 greeting asking for CURVE followed by a garbage HELLO command.
  std::string greeting(64, '\0');
  greeting[0] = '\xff';
  greeting[9] = '\x7f';
  greeting[10] = 3;
  greeting.replace(12, 5, "CURVE");
  refused0 = RefusedHandshakes();
  SendRawTcp(PortOf(pub.Raw().Endpoint()), greeting + std::string("\x04\x10garbage-garbage!", 18));
  CHECK(WaitUntil([&] { return RefusedHandshakes() > refused0; }));
  CHECK(WaitUntil([&] { return log.Text().find("malformed handshake") != std::string::npos; }));
  // Bytes that are not ZMTP at all.
  refused0 = RefusedHandshakes();
  SendRawTcp(PortOf(pub.Raw().Endpoint()), std::string(200, 'x'));
  CHECK(WaitUntil([&] { return RefusedHandshakes() > refused0; }));
  CHECK(WaitUntil([&] { return log.Text().find("wrong server key") != std::string::npos; }));
}

TEST_CASE("CURVE: services answer listed clients only", "[integration]") {
  ScopedRunDir dir;
  Keys keys;
  ScopedCurve curve(keys);
  ServiceServerOptions so;
  so.endpoint = "tcp://127.0.0.1:*";
  RawServiceServer server("/secure_svc", "PoseStamped", "/test", so,
                          [](const msgs::WireMessage& req, uint64_t, msgs::WireMessage* rep,
                             std::string*) {
                            *rep = req;
                            return true;
                          });
  std::atomic<bool> stop{false};
  std::thread serve([&] {
    while (!stop) {
      zmq::pollitem_t item{server.Socket().handle(), 0, ZMQ_POLLIN, 0};
      zmq::poll(&item, 1, std::chrono::milliseconds(10));
      server.Drain();
    }
  });
  ServiceClientOptions co;
  co.endpoint = server.Endpoint();
  co.timeout = std::chrono::milliseconds(2000);
  co.retries = 1;
  RawServiceClient client("/secure_svc", co);
  msgs::WireMessage reply;
  std::string error;
  CHECK(client.Call(msgs::Encode(Pose(1.5)), &reply, &error));
  const uint64_t handled = server.Stats().requests.load();

  // A plain DEALER sending a well-formed request never gets it handled.
  zmq::socket_t plain(ZmqContext(), zmq::socket_type::dealer);
  plain.set(zmq::sockopt::linger, 0);
  const uint64_t refused0 = RefusedHandshakes();
  plain.connect(server.Endpoint());
  plain.send(zmq::message_t(), zmq::send_flags::sndmore);
  plain.send(zmq::buffer(std::string(8, '\1')), zmq::send_flags::sndmore);
  plain.send(zmq::buffer(msgs::Encode(Pose(2)).header), zmq::send_flags::none);
  CHECK(WaitUntil([&] { return RefusedHandshakes() > refused0; }));
  zmq::message_t m;
  CHECK_FALSE(plain.recv(m, zmq::recv_flags::dontwait));
  CHECK(server.Stats().requests.load() == handled);
  stop = true;
  serve.join();
}
