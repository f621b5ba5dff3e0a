/// @file pipeline_test_util.h
/// @brief Helpers of the pipeline tests: a graph started with `p2i launch` (output captured in
/// a file), NodeStatus readers, pids from the discovery registry, summary.json and files.
#pragma once

#include <dirent.h>
#include <signal.h>

#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "msgs/codec.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/service_client.h"
#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"

namespace p2i::pipeline::testing {

using Clock = std::chrono::steady_clock;
/// A client of the graph's render service (the synthesizer's, or the pool's).
using RenderClient = runtime::ServiceClient<msgs::pb::RenderRequest, msgs::RenderReplyMsg>;

/// A launch file started through `p2i launch` in a private run dir (also exported as
/// P2I_RUN_DIR to this process, so the test's clients and publishers find the graph's ipc
/// endpoints). stdout + stderr of the launcher (and so of every node) go to `<run>/launch.log`.
class LaunchedGraph {
 public:
  /// Creates the run dir (the test may bind endpoints in it); Start() launches.
  LaunchedGraph() {
    out_ = run_.Path() + "/out";
    log_ = run_.Path() + "/launch.log";
  }
  void Start(const std::string& launch_file, const std::vector<std::string>& args = {}) {
    std::string cmd = "exec '" + p2i::testing::BinDir() + "/p2i' launch '" + launch_file +
                      "' --run-dir '" + run_.Path() + "' --grace-period 5 out:=" + out_ +
                      " run:=" + run_.Path();
    for (const auto& a : args) cmd += " '" + a + "'";
    cmd += " >'" + log_ + "' 2>&1";
    launcher_ = std::make_unique<p2i::testing::Process>(
        std::vector<std::string>{"/bin/sh", "-c", cmd});
  }
  /// A test that ends by a failed REQUIRE (an exception unwinding through here) gets the graph's
  /// log on stderr: an INFO(Log()) written at the start would show only the log of that moment.
  ~LaunchedGraph() {
    if (launcher_ && launcher_->Running()) launcher_->Terminate();
    if (std::uncaught_exceptions() > 0)
      std::cerr << "---- launch log of the failed test (" << log_ << ") ----\n"
                << Log() << "---- end ----\n";
  }

  const std::string& Run() const { return run_.Path(); }
  const std::string& Out() const { return out_; }
  /// SIGTERM to the launcher (every node gets SIGTERM); its exit code.
  int Stop() { return launcher_->Terminate(); }
  bool Running() const { return launcher_->Running(); }
  std::string Log() const { return p2i::testing::ReadFile(log_); }

 private:
  runtime::testing::ScopedRunDir run_;
  std::string out_, log_;
  std::unique_ptr<p2i::testing::Process> launcher_;
};

/// The live pid that registered a `kind` ("topic"/"service") endpoint whose registry file name
/// contains `name_part`, or -1.
inline int RegisteredPid(const std::string& run_dir, const std::string& kind,
                         const std::string& name_part) {
  const std::string dir = run_dir + "/registry";
  if (!std::filesystem::exists(dir)) return -1;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    const size_t dot = f.find('.');
    if (dot == std::string::npos) continue;
    if (f.compare(dot + 1, kind.size(), kind) != 0) continue;
    if (f.find(name_part) == std::string::npos) continue;
    const int pid = std::atoi(f.substr(0, dot).c_str());
    if (pid > 0 && ::kill(pid, 0) == 0) return pid;
  }
  return -1;
}

/// Subscribes to every node's "~/status" and keeps the newest NodeStatus of each.
class StatusWatcher {
 public:
  explicit StatusWatcher(const std::vector<std::string>& nodes) {
    for (const auto& n : nodes) subs_[n] = std::make_unique<runtime::RawSubscriber>(
        n + "/status", runtime::SubscriberOptions{});
  }
  /// Drains the subscriptions (waiting up to `wait` for something new).
  void Poll(std::chrono::milliseconds wait = std::chrono::milliseconds(50)) {
    for (auto& [node, sub] : subs_) {
      msgs::WireMessage wire;
      msgs::pb::Header header;
      auto w = wait;
      while (sub->Receive(&wire, &header, w)) {
        msgs::pb::NodeStatus s;
        std::string error;
        if (msgs::Decode(wire, &s, &error)) latest_[node] = s;
        w = std::chrono::milliseconds(0);
      }
    }
  }
  bool Has(const std::string& node) const { return latest_.count(node) > 0; }
  uint64_t Counter(const std::string& node, const std::string& key) const {
    const auto it = latest_.find(node);
    if (it == latest_.end()) return 0;
    const auto c = it->second.counters().find(key);
    return c == it->second.counters().end() ? 0 : c->second;
  }
  double Value(const std::string& node, const std::string& key) const {
    const auto it = latest_.find(node);
    if (it == latest_.end()) return 0.0;
    const auto v = it->second.values().find(key);
    return v == it->second.values().end() ? 0.0 : v->second;
  }
  /// Every node's newest counters and values, one node per line (for failure messages: Catch's
  /// INFO builds its text when it runs, so it must run after the wait it explains).
  std::string Describe() const {
    std::string out;
    for (const auto& [node, s] : latest_) {
      out += node + ":";
      for (const auto& [k, v] : s.counters()) out += " " + k + "=" + std::to_string(v);
      for (const auto& [k, v] : s.values()) out += " " + k + "=" + std::to_string(v);
      out += "\n";
    }
    for (const auto& [node, sub] : subs_)
      if (!latest_.count(node)) out += node + ": no status received\n";
    return out;
  }
  /// Polls until `cond()` holds or `timeout` passes; returns cond().
  bool WaitFor(const std::function<bool()>& cond, std::chrono::seconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      Poll();
      if (cond()) return true;
    }
    return cond();
  }

 private:
  std::map<std::string, std::unique_ptr<runtime::RawSubscriber>> subs_;
  std::map<std::string, msgs::pb::NodeStatus> latest_;
};

/// summary.json of a slam_sink output folder (null if missing or being replaced).
inline nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception&) {
    return nullptr;
  }
}

/// The data lines of a TUM index file (comments skipped), split at whitespace.
inline std::vector<std::vector<std::string>> ReadIndex(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::vector<std::string> row;
    std::string tok;
    while (ls >> tok) row.push_back(tok);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace p2i::pipeline::testing
