/// @file node_test.cc
/// @brief Node base in-process (typed pub/sub on the executor, status, latching, remapping) and
/// as a real process (SIGTERM shutdown, unknown parameter exit code, remapping from the CLI).
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <thread>

#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/node.h"
#include "nodes/runtime/shutdown.h"
#include "tests/read_file.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"

using namespace p2i;
using namespace p2i::runtime;
using p2i::runtime::testing::ScopedRunDir;
using p2i::runtime::testing::WaitUntil;

namespace {

NodeArgs Args(std::vector<std::string> v) { return NodeArgs::Parse(v); }

msgs::pb::PoseStamped Pose(double x) {
  msgs::pb::PoseStamped m;
  m.mutable_pose()->mutable_position()->set_x(x);
  m.mutable_pose()->mutable_orientation()->set_w(1.0);
  return m;
}

/// Spins `nodes` on this thread until `cond` or 5 s.
bool SpinUntil(std::vector<Node*> nodes, const std::function<bool()>& cond) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < deadline) {
    for (auto* n : nodes) n->SpinOnce(std::chrono::milliseconds(2));
    if (cond()) return true;
  }
  return false;
}

/// A child process running runtime_test_node; killed (SIGKILL) if still alive at destruction.
class ChildNode {
 public:
  explicit ChildNode(const std::vector<std::string>& args) {
    const std::string exe = p2i::testing::BinDir() + "/runtime_test_node";
    err_path_ = std::string(std::getenv("P2I_RUN_DIR")) + "/child_stderr." +
                std::to_string(counter_++);
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(err_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      dup2(fd, 2);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(exe.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
  }
  ~ChildNode() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  /// Waits up to `timeout` for exit; returns the exit code, or -1 on timeout/signal.
  int Wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return -1;
  }
  void Signal(int sig) { kill(pid_, sig); }
  std::string Stderr() const { return p2i::testing::ReadFile(err_path_); }
  int Pid() const { return pid_; }

 private:
  static inline int counter_ = 0;
  pid_t pid_ = -1;
  bool exited_ = false;
  std::string err_path_;
};

bool Registered(const std::string& topic) {
  for (const auto& e : Registry::List()) {
    if (e.kind == "topic" && e.name == topic) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("Node: typed pub/sub on the executor, with namespace and remapping", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  Node talker("talker", Args({"--namespace", "/robot", "-r", "chatter:=/shared/chatter"}));
  Node listener("listener", Args({}));
  auto pub = talker.Advertise<msgs::pb::PoseStamped>("chatter");
  CHECK(pub->Topic() == "/shared/chatter");
  std::vector<double> xs;
  std::vector<std::string> publishers;
  listener.Subscribe<msgs::pb::PoseStamped>("/shared/chatter",
                                            [&](const msgs::pb::PoseStamped& m) {
                                              xs.push_back(m.pose().position().x());
                                              publishers.push_back(m.header().publisher());
                                            });
  double x = 0;
  REQUIRE(SpinUntil({&talker, &listener}, [&] {
    pub->Publish(Pose(++x));
    return xs.size() >= 3;
  }));
  CHECK(publishers.front() == "/robot/talker");
  for (size_t i = 1; i < xs.size(); ++i) CHECK(xs[i] == xs[i - 1] + 1);
  CHECK(listener.MakeStatus().counters().at("received") >= 3);
  CHECK(listener.MakeStatus().counters().at("dropped") == 0);
}

TEST_CASE("Node: status is published and latched data reaches a late joiner", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  Node cam("cam", Args({"status_period:=0.05", "latch_period:=0.05"}));
  PublisherOptions latched;
  latched.latched = true;
  auto info_pub = cam.Advertise<msgs::pb::CameraInfo>("camera_info", latched);
  msgs::pb::CameraInfo info;
  info.set_width(640);
  info.set_height(480);
  info.set_camera_name("cam0");
  info.set_distortion_model("plumb_bob");
  for (double k : {585.0, 0.0, 320.0, 0.0, 585.0, 240.0, 0.0, 0.0, 1.0}) info.add_k(k);
  info_pub->Publish(info);  // before anyone listens
  cam.Start();
  for (int i = 0; i < 5; ++i) cam.SpinOnce(std::chrono::milliseconds(10));

  Node late("late", Args({}));
  std::vector<std::string> names;
  std::vector<msgs::pb::NodeStatus> statuses;
  late.Subscribe<msgs::pb::CameraInfo>(
      "camera_info", [&](const msgs::pb::CameraInfo& m) { names.push_back(m.camera_name()); });
  late.Subscribe<msgs::pb::NodeStatus>(
      "/cam/status", [&](const msgs::pb::NodeStatus& s) { statuses.push_back(s); });
  REQUIRE(SpinUntil({&cam, &late}, [&] { return !names.empty() && statuses.size() >= 2; }));
  CHECK(names.front() == "cam0");
  CHECK(statuses.back().node() == "/cam");
  CHECK(statuses.back().alive());
  CHECK(statuses.back().counters().at("published") >= 1);
  CHECK(statuses.back().uptime_s() > 0);
}

TEST_CASE("Node: an undeclared parameter is a start-up error", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  Node n("n", Args({"rate:=5", "ratee:=6"}));
  n.Declare<double>("rate", 1.0, "rate");
  try {
    n.Start();
    FAIL("expected StartupError");
  } catch (const StartupError& e) {
    CHECK(std::string(e.what()).find("'ratee' (from command line)") != std::string::npos);
  }
}

TEST_CASE("Node: typed service through the executor, request ids in headers", "[unit]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  Node server("server", Args({}));
  server.Serve<msgs::pb::PoseRequest, msgs::pb::PoseStamped>(
      "mirror", [](const msgs::pb::PoseRequest& r, msgs::pb::PoseStamped* out, std::string*) {
        *out->mutable_pose() = r.pose();
        out->mutable_pose()->mutable_position()->set_x(-r.pose().position().x());
        return true;
      });
  server.Start();
  std::atomic<bool> done{false};
  std::thread spinner([&] {
    while (!done) server.SpinOnce(std::chrono::milliseconds(5));
  });
  Node client_node("client", Args({}));
  auto client = client_node.Client<msgs::pb::PoseRequest, msgs::pb::PoseStamped>("mirror");
  msgs::pb::PoseRequest req;
  req.mutable_pose()->mutable_position()->set_x(2.5);
  req.mutable_pose()->mutable_orientation()->set_w(1.0);
  msgs::pb::PoseStamped reply;
  std::string error;
  const bool ok = client->Call(req, &reply, &error);
  done = true;
  spinner.join();
  REQUIRE(ok);
  CHECK(reply.pose().position().x() == -2.5);
  CHECK(reply.header().request_id() != 0);
  CHECK(reply.header().publisher() == "/server");
}

TEST_CASE("Node process: SIGTERM stops it cleanly (well within the wait bound) with exit code 0",
          "[integration]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  const std::string marker = run_dir.Path() + "/marker";
  ChildNode child({"--name", "worker", "shutdown_marker:=" + marker, "rate:=100"});
  REQUIRE(WaitUntil([] { return Registered("/chatter"); }));
  const int sig = GENERATE(SIGTERM, SIGINT);
  const auto t0 = std::chrono::steady_clock::now();
  child.Signal(sig);
  const int code = child.Wait(std::chrono::milliseconds(10000));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO("stderr: " << child.Stderr() << "\nshutdown took " << seconds << " s");
  CHECK(code == 0);
  // The contract (docs/cli_contract) is a clean shutdown within 1 s on an idle machine. This is
  // not a timing test: on a loaded 2-core box scheduling alone can take a second, so the bound
  // here only catches a node that hangs (a missed wake-up, a blocking socket close), with 5x
  // margin. A missing shutdown would run into the 10 s wait above and fail `code == 0`.
  CHECK(seconds < 5.0);
  std::ifstream in(marker);
  CHECK(in.good());  // OnShutdown ran
  CHECK_FALSE(Registered("/chatter"));  // registry entry removed on close
  CHECK(child.Stderr().find("[/worker]") != std::string::npos);  // node name in log lines
}

TEST_CASE("Node process: unknown parameter exits 2 naming it and its source", "[integration]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  const std::string file = run_dir.Path() + "/p.yaml";
  std::ofstream(file) << "rate: 10\nbogus_from_file: 1\n";
  ChildNode child({"--params-file", file, "frame_id:=cam"});
  CHECK(child.Wait(std::chrono::milliseconds(5000)) == 2);
  const std::string err = child.Stderr();
  INFO(err);
  CHECK(err.find("'bogus_from_file'") != std::string::npos);
  CHECK(err.find(file) != std::string::npos);
}

TEST_CASE("Node process: a bad P2I_HEAP exits 2 naming the variable and its choices",
          "[integration]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  setenv("P2I_HEAP", "fast", 1);
  ChildNode child({"frame_id:=cam"});
  const int code = child.Wait(std::chrono::milliseconds(5000));
  unsetenv("P2I_HEAP");
  CHECK(code == 2);
  const std::string err = child.Stderr();
  INFO(err);
  CHECK(err.find("configuration error") != std::string::npos);
  CHECK(err.find("P2I_HEAP='fast'") != std::string::npos);
  CHECK(err.find("P2I_HEAP=system") != std::string::npos);
}

TEST_CASE("Node process: remapped topic and service reach another process", "[integration]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  ChildNode child({"--namespace", "/r1", "-r", "chatter:=/remapped/chatter", "-r",
                   "echo:=/remapped/echo", "frame_id:=proc"});
  Node me("me", Args({}));
  std::vector<std::string> frames;
  me.Subscribe<msgs::pb::PoseStamped>(
      "/remapped/chatter", [&](const msgs::pb::PoseStamped& m) { frames.push_back(m.header().frame_id()); });
  REQUIRE(SpinUntil({&me}, [&] { return frames.size() >= 2; }));
  CHECK(frames.front() == "proc");
  ServiceClientOptions co;
  co.timeout = std::chrono::milliseconds(500);
  co.retries = 5;
  auto client = me.Client<msgs::pb::PoseRequest, msgs::pb::PoseStamped>("/remapped/echo", co);
  msgs::pb::PoseRequest req;
  req.mutable_pose()->mutable_position()->set_y(4.0);
  req.mutable_pose()->mutable_orientation()->set_w(1.0);
  msgs::pb::PoseStamped reply;
  std::string error;
  REQUIRE(client->Call(req, &reply, &error));
  CHECK(reply.pose().position().y() == 4.0);
  CHECK(reply.header().publisher() == "/r1/test_node");
  child.Signal(SIGTERM);
  CHECK(child.Wait(std::chrono::milliseconds(3000)) == 0);
}

TEST_CASE("Node process: a client retries across a server process that dies and comes back",
          "[integration]") {
  Shutdown::ResetForTesting();
  ScopedRunDir run_dir;
  Node me("me", Args({}));
  ServiceClientOptions co;
  co.timeout = std::chrono::milliseconds(300);
  co.retries = 20;
  auto client = me.Client<msgs::pb::PoseRequest, msgs::pb::PoseStamped>("/echo", co);
  msgs::pb::PoseRequest req;
  req.mutable_pose()->mutable_orientation()->set_w(1.0);
  msgs::pb::PoseStamped reply;
  std::string error;
  {
    ChildNode first({});
    REQUIRE(client->Call(req, &reply, &error));
    first.Signal(SIGKILL);  // dies without any clean-up
    first.Wait(std::chrono::milliseconds(2000));
  }
  ChildNode second({"--name", "second"});
  REQUIRE(client->Call(req, &reply, &error));
  CHECK(reply.header().publisher() == "/second");
  second.Signal(SIGTERM);
  CHECK(second.Wait(std::chrono::milliseconds(3000)) == 0);
}
