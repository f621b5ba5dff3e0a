/// @file node.h
/// @brief Node base: identity, parameters, logging, pub/sub, services, timers, status, signals.
#pragma once

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "msgs/codec.h"
#include "nodes/runtime/executor.h"
#include "nodes/runtime/names.h"
#include "nodes/runtime/node_args.h"
#include "nodes/runtime/param_service.h"
#include "nodes/runtime/parameters.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_service.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/service_client.h"
#include "util/heap_policy.h"

namespace p2i::runtime {

/// Thrown under --help when the node is about to create something (ParametersDone(), or the
/// first publisher, subscription, service, client or timer): what() is the parameter help.
/// RunNode() prints it and exits 0, so `--help` never creates files or sockets.
class HelpRequested : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The p2i version (the CMake project version), for --version.
const char* Version();

/// The base of every node process.
///
/// Construction parses nothing itself: it takes NodeArgs (the command line), loads parameter
/// files and overrides, sets up the logger (spdlog, "[node full name]" in every line) and
/// installs SIGINT/SIGTERM handlers. A derived node declares its parameters with Declare<T>()
/// and creates publishers, subscriptions, services and timers in its constructor; Spin() then
/// checks that every supplied parameter was declared (StartupError otherwise), publishes
/// NodeStatus on "~/status" every `status_period` s, re-publishes latched topics every
/// `latch_period` s, and runs callbacks until SIGINT/SIGTERM or Stop(). On return, sockets
/// are closed (linger 0) and the log flushed; a signal stops it within ~100 ms.
///
/// Base parameters (every node has them): status_period (s, 0 = off), latch_period (s),
/// log_level (trace|debug|info|warn|error), endpoints (map resolved-or-given name -> endpoint,
/// e.g. {rgbd: "tcp://127.0.0.1:5555"}; a subscription may list several, comma-separated).
///
/// Thread-safety: thread-compatible. Everything (construction, creating endpoints, Spin) runs on
/// one thread, the node's executor thread; callbacks and timers run on it, one at a time. Each
/// subscription/service socket is owned by that thread. Publishers may also be used from other
/// threads (they lock). Counter updates (Count) are thread-safe.
class Node {
 public:
  Node(const std::string& default_name, const NodeArgs& args);
  virtual ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& Name() const { return names_.NodeName(); }
  const std::string& Namespace() const { return names_.Namespace(); }
  std::string FullName() const { return names_.FullNodeName(); }
  const NodeArgs& Args() const { return args_; }
  spdlog::logger& Log() const { return *logger_; }
  std::shared_ptr<spdlog::logger> Logger() const { return logger_; }
  Parameters& Params() { return params_; }
  /// Resolves a topic/service name under the namespace and applies remapping.
  std::string Resolve(const std::string& name) const { return names_.Resolve(name); }

  /// Call once every parameter is declared (and the node's options validated), before creating
  /// anything on disk or on the network: rejects supplied parameters nobody declared
  /// (StartupError, exit 2) and, under --help, ends the construction (HelpRequested). Spin()
  /// and Start() run the same check later for nodes that do not call it.
  void ParametersDone();

  /// Declares a parameter (see Parameters::Declare).
  template <class T>
  T Declare(const std::string& name, const T& default_value, const std::string& description) {
    return params_.Declare<T>(name, default_value, description);
  }
  /// Declares a parameter that `p2i param set` may change while the node runs: `on_set` runs
  /// on the executor thread with the new value (it may throw to refuse it; the error reaches
  /// the caller). Returns the start-up value.
  template <class T>
  T DeclareDynamic(const std::string& name, const T& default_value, const std::string& description,
                   std::function<void(const T&)> on_set) {
    const T value = params_.Declare<T>(name, default_value, description);
    dynamic_[name] = [on_set](const YAML::Node& v) { on_set(v.as<T>()); };
    return value;
  }

  // ---- topics
  std::shared_ptr<RawPublisher> AdvertiseRaw(const std::string& topic,
                                             const std::string& type_name,
                                             PublisherOptions options = {});
  template <class T>
  std::shared_ptr<Publisher<T>> Advertise(const std::string& topic,
                                          PublisherOptions options = {}) {
    return std::make_shared<Publisher<T>>(
        AdvertiseRaw(topic, msgs::TypeName(msgs::TypeOf<T>()), options), FullName());
  }

  /// `handler` runs on the executor thread for every well-formed message.
  std::shared_ptr<RawSubscriber> SubscribeRaw(const std::string& topic,
                                              RawSubscriber::Handler handler,
                                              SubscriberOptions options = {});
  /// Decodes each message as T; failures are counted as malformed and logged (rate-limited),
  /// never delivered.
  template <class T>
  std::shared_ptr<RawSubscriber> Subscribe(const std::string& topic,
                                           std::function<void(const T&)> callback,
                                           SubscriberOptions options = {}) {
    const std::string resolved = Resolve(topic);
    return SubscribeRaw(
        topic,
        [this, callback, resolved](msgs::WireMessage&& wire, const msgs::pb::Header&) {
          T msg;
          std::string error;
          if (!msgs::Decode(wire, &msg, &error)) {
            WarnThrottled("decode:" + resolved,
                          "dropping undecodable message on " + resolved + ": " + error);
            return false;
          }
          callback(msg);
          return true;
        },
        options);
  }

  // ---- services
  /// Serves `name`: `handler(request, reply, error)` runs on the executor thread.
  template <class Req, class Rep>
  std::shared_ptr<RawServiceServer> Serve(
      const std::string& name, std::function<bool(const Req&, Rep*, std::string*)> handler,
      ServiceServerOptions options = {}) {
    const std::string node = FullName();
    auto raw_handler = [handler, node](const msgs::WireMessage& wire, uint64_t id,
                                       msgs::WireMessage* out, std::string* error) {
      Req request;
      std::string why;
      if (!msgs::Decode(wire, &request, &why)) {
        *error = "malformed request: " + why;
        return false;
      }
      Rep reply;
      if (!handler(request, &reply, error)) return false;
      msgs::pb::Header* h = msgs::MutableHeader(reply);
      h->set_request_id(id);
      h->set_seq(id);
      h->set_publish_stamp_ns(NowNs());
      h->set_publisher(node);
      *out = msgs::Encode(reply);
      return true;
    };
    return ServeRaw(name, msgs::TypeName(msgs::TypeOf<Req>()), raw_handler, options);
  }
  std::shared_ptr<RawServiceServer> ServeRaw(const std::string& name,
                                             const std::string& type_name,
                                             RawServiceServer::Handler handler,
                                             ServiceServerOptions options = {});
  /// A client for `name` (endpoint from the `endpoints` parameter or the default). The client
  /// is used on the calling thread only.
  template <class Req, class Rep>
  std::unique_ptr<ServiceClient<Req, Rep>> Client(const std::string& name,
                                                 ServiceClientOptions options = {}) {
    BeforeSideEffect();
    const std::string resolved = Resolve(name);
    if (options.endpoint.empty()) options.endpoint = EndpointFor(name, resolved);
    if (options.endpoint.empty() && !peers_.empty() && !options.resolver) {
      // Multi-host launch: the server may be on another host (found on every reconnect).
      options.resolver = [resolved, peers = peers_] {
        return FindServiceEndpoint(resolved, peers, std::chrono::milliseconds(300));
      };
    }
    return std::make_unique<ServiceClient<Req, Rep>>(resolved, FullName(), options);
  }

  // ---- timers, loop
  int AddTimer(std::chrono::nanoseconds period, std::function<void()> cb) {
    BeforeSideEffect();
    return executor_.AddTimer(period, std::move(cb));
  }
  Executor& GetExecutor() { return executor_; }
  /// Checks parameters, then runs until SIGINT/SIGTERM or Stop(); then OnShutdown() and close.
  void Spin();
  /// For nodes with their own loop: call once before the loop (checks parameters, starts status
  /// and latch timers), then SpinOnce() in the loop while Ok().
  void Start();
  bool SpinOnce(std::chrono::nanoseconds max_wait = std::chrono::milliseconds(0));
  bool Ok() const { return !executor_.Stopped(); }
  void Stop() { executor_.Stop(); }

  // ---- status
  /// Adds to a named counter reported in NodeStatus. Thread-safe.
  void Count(const std::string& key, uint64_t n = 1);
  /// Sets a named value reported in NodeStatus. Thread-safe.
  void SetValue(const std::string& key, double value);
  /// The NodeStatus that would be published now (counters summed over all endpoints).
  msgs::pb::NodeStatus MakeStatus() const;
  /// Logs a warning at most once per second per key (bad input must not flood the log).
  void WarnThrottled(const std::string& key, const std::string& text);

 protected:
  /// Called once after the loop stops and before sockets close (flush files here).
  virtual void OnShutdown() {}
  /// The `endpoints` entry for a topic/service (resolved name first, then as given), or "".
  /// Marks the name used: an `endpoints` key no lookup asked for is a start-up error.
  std::string EndpointFor(const std::string& given, const std::string& resolved) const;

 private:
  /// Under --help: throws HelpRequested (nothing may be created).
  void BeforeSideEffect() const;
  void Close();

  NodeArgs args_;
  NameResolver names_;
  Parameters params_;
  std::shared_ptr<spdlog::logger> logger_;
  Executor executor_;
  std::map<std::string, ParamService::Setter> dynamic_;
  std::unique_ptr<ParamService> param_service_;
  std::map<std::string, std::string> endpoints_;
  mutable std::set<std::string> endpoint_names_used_;  // given and resolved names looked up
  std::vector<std::string> peers_;        ///< $P2I_PEERS (multi-host launch)
  std::map<std::string, std::string> pools_;  ///< `pool` parameter: service -> broker backend
  std::unique_ptr<PeerWatcher> watcher_;  ///< finds remote publishers of subscribed topics
  double status_period_s_ = 1.0;
  double latch_period_s_ = 1.0;
  bool started_ = false;
  bool closed_ = false;
  std::chrono::steady_clock::time_point start_time_;
  std::vector<std::shared_ptr<RawPublisher>> publishers_;
  std::vector<std::shared_ptr<RawSubscriber>> subscribers_;
  std::vector<std::shared_ptr<RawServiceServer>> servers_;
  std::shared_ptr<Publisher<msgs::pb::NodeStatus>> status_pub_;
  mutable std::mutex counters_mutex_;
  std::map<std::string, uint64_t> counters_;
  std::map<std::string, double> values_;
  std::map<std::string, std::chrono::steady_clock::time_point> last_warn_;
};

/// Prints a node's --help: usage, its declared parameters (type, default, description) and
/// the exit codes.
void PrintNodeHelp(const std::string& executable, const std::string& parameters_help);

/// Runs a node class with the standard exit codes (docs/RUNTIME.md): 0 after a clean shutdown
/// (and for --help / --version), 2 for a usage or configuration error (bad command line,
/// unknown or ill-typed parameter, a StartupError or std::invalid_argument thrown before the
/// node runs, e.g. by its options' Validate()), 1 for any other failure (a runtime error).
/// NodeT must be constructible from (const NodeArgs&).
template <class NodeT>
int RunNode(int argc, char** argv) {
  std::string exe = argc > 0 ? argv[0] : "node";
  if (exe.find('/') != std::string::npos) exe = exe.substr(exe.rfind('/') + 1);
  if (!util::ApplyHeapPolicyOrReport(exe)) return 2;  // P2I_HEAP, before any thread starts
  NodeArgs args;
  try {
    args = NodeArgs::Parse(argc, argv);
  } catch (const StartupError& e) {
    std::fprintf(stderr, "%s: usage error: %s\n", exe.c_str(), e.what());
    return 2;
  }
  if (args.version) {
    std::printf("%s %s\n", exe.c_str(), Version());
    return 0;
  }
  bool running = false;
  try {
    NodeT node(args);
    if (args.help) {
      PrintNodeHelp(exe, node.Params().Help());
      return 0;
    }
    node.Start();
    running = true;
    node.Spin();
    return 0;
  } catch (const HelpRequested& h) {
    PrintNodeHelp(exe, h.what());
    return 0;
  } catch (const StartupError& e) {
    std::fprintf(stderr, "%s: start-up error: %s\n", exe.c_str(), e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: %s: %s\n", exe.c_str(),
                 running ? "error" : "configuration error", e.what());
    return running ? 1 : 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", exe.c_str(), e.what());
    return 1;
  }
}

}  // namespace p2i::runtime
