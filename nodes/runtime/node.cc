/// @file node.cc
/// @brief Node base: set-up, endpoint parameters, status and latch timers, shutdown.
#include "nodes/runtime/node.h"

#include <sstream>

#include <spdlog/sinks/stdout_color_sinks.h>

#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/shutdown.h"

namespace p2i::runtime {
namespace {

std::vector<std::string> SplitCommas(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, ',')) {
    const auto b = part.find_first_not_of(" \t");
    const auto e = part.find_last_not_of(" \t");
    if (b != std::string::npos) out.push_back(part.substr(b, e - b + 1));
  }
  return out;
}

}  // namespace

Node::Node(const std::string& default_name, const NodeArgs& args)
    : args_(args),
      names_(args.node_namespace, args.name.empty() ? default_name : args.name, args.remaps),
      params_(args, names_.NodeName(), names_.FullNodeName()),
      start_time_(std::chrono::steady_clock::now()) {
  Shutdown::InstallSignalHandlers();
  auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  logger_ = std::make_shared<spdlog::logger>(FullName(), sink);
  logger_->set_pattern("[%H:%M:%S.%e] [%^%l%$] [%n] %v");
  logger_->flush_on(spdlog::level::warn);
  CurveSecurity::SetLogger(logger_);  // refused peers appear in this node's log

  const auto parse_level = [](const std::string& level) {
    const auto lvl = spdlog::level::from_str(level);
    if (lvl == spdlog::level::off && level != "off") {
      throw StartupError("parameter 'log_level': '" + level +
                         "' is not one of trace, debug, info, warn, error, off");
    }
    return lvl;
  };
  const std::string level = DeclareDynamic<std::string>(
      "log_level", "info", "log level: trace, debug, info, warn, error (dynamic)",
      [this, parse_level](const std::string& l) { logger_->set_level(parse_level(l)); });
  logger_->set_level(parse_level(level));
  status_period_s_ = Declare<double>("status_period", 1.0,
                                     "seconds between NodeStatus messages on ~/status (0 = off)");
  latch_period_s_ = Declare<double>("latch_period", 1.0,
                                    "seconds between re-publications of latched topics");
  endpoints_ = Declare<std::map<std::string, std::string>>(
      "endpoints", {},
      "endpoint per topic/service name (as written or resolved), e.g. {rgbd: "
      "tcp://127.0.0.1:5555}; default ipc:// under $P2I_RUN_DIR");
  if (latch_period_s_ <= 0) throw StartupError("parameter 'latch_period' must be > 0");
  peers_ = PeerRegistries();
  pools_ = Declare<std::map<std::string, std::string>>(
      "pool", {},
      "serve these services as a worker of a pool broker (nodes/pool): service name -> the "
      "broker's backend endpoint ('' = its default ipc endpoint), e.g. {render: ''}");
}

Node::~Node() { Close(); }

const char* Version() { return P2I_VERSION; }

void PrintNodeHelp(const std::string& executable, const std::string& parameters_help) {
  std::printf(
      "usage: %s [--name NAME] [--namespace NS] [--params-file FILE]... [-r FROM:=TO]...\n"
      "       %*s [NAME:=VALUE]...   (ROS 2 spellings: --ros-args, -p NAME:=VALUE, --remap)\n"
      "       %s --help | --version\n\n"
      "Parameters (NAME:=VALUE on the command line, VALUE is YAML; or a --params-file, plain\n"
      "or ROS 2 format):\n%s\n"
      "Exit codes: 0 clean shutdown, 1 runtime error, 2 usage or configuration error.\n"
      "See docs/RUNTIME.md.\n",
      executable.c_str(), static_cast<int>(executable.size()), "", executable.c_str(),
      parameters_help.c_str());
}

void Node::BeforeSideEffect() const {
  if (args_.help) throw HelpRequested(params_.Help());
}

void Node::ParametersDone() {
  BeforeSideEffect();
  params_.CheckAllDeclared();
}

std::string Node::EndpointFor(const std::string& given, const std::string& resolved) const {
  endpoint_names_used_.insert(given);
  endpoint_names_used_.insert(resolved);
  auto it = endpoints_.find(resolved);
  if (it == endpoints_.end()) it = endpoints_.find(given);
  return it == endpoints_.end() ? "" : it->second;
}

std::shared_ptr<RawPublisher> Node::AdvertiseRaw(const std::string& topic,
                                                 const std::string& type_name,
                                                 PublisherOptions options) {
  BeforeSideEffect();
  const std::string resolved = Resolve(topic);
  if (options.endpoint.empty()) options.endpoint = EndpointFor(topic, resolved);
  auto pub = std::make_shared<RawPublisher>(resolved, type_name, FullName(), options);
  publishers_.push_back(pub);
  logger_->debug("publishing {} ({}) on {}", resolved, type_name, pub->Endpoint());
  return pub;
}

std::shared_ptr<RawSubscriber> Node::SubscribeRaw(const std::string& topic,
                                                  RawSubscriber::Handler handler,
                                                  SubscriberOptions options) {
  BeforeSideEffect();
  const std::string resolved = Resolve(topic);
  if (options.endpoints.empty()) options.endpoints = SplitCommas(EndpointFor(topic, resolved));
  const bool discover = options.endpoints.empty() && !peers_.empty();
  auto sub = std::make_shared<RawSubscriber>(resolved, options);
  subscribers_.push_back(sub);
  RawSubscriber* raw = sub.get();
  if (discover) {  // multi-host launch: also connect to publishers the peers list
    if (!watcher_) watcher_ = std::make_unique<PeerWatcher>(peers_, std::chrono::milliseconds(500));
    watcher_->Watch("topic", resolved, [this, raw](const std::vector<std::string>& eps) {
      executor_.Post([this, raw, eps] {
        for (const auto& ep : eps) {
          raw->Connect(ep);
          logger_->info("subscribed to {} at {} (found on a peer)", raw->Topic(), ep);
        }
      });
    });
  }
  executor_.AddSocket(&sub->Socket(), [this, raw, handler] {
    const uint64_t malformed_before = raw->Stats().malformed.load();
    raw->Drain(handler);
    if (raw->Stats().malformed.load() != malformed_before && !raw->LastError().empty()) {
      WarnThrottled("malformed:" + raw->Topic(),
                    "dropping malformed message on " + raw->Topic() + ": " + raw->LastError());
    }
  });
  logger_->debug("subscribed to {} at {}", resolved, sub->Endpoints().front());
  return sub;
}

std::shared_ptr<RawServiceServer> Node::ServeRaw(const std::string& name,
                                                 const std::string& type_name,
                                                 RawServiceServer::Handler handler,
                                                 ServiceServerOptions options) {
  BeforeSideEffect();
  const std::string resolved = Resolve(name);
  if (options.endpoint.empty()) options.endpoint = EndpointFor(name, resolved);
  auto pool = pools_.find(resolved);
  if (pool == pools_.end()) pool = pools_.find(name);
  if (pool != pools_.end() && options.worker_of.empty())
    options.worker_of = pool->second.empty() ? DefaultEndpoint("pool", resolved) : pool->second;
  auto server = std::make_shared<RawServiceServer>(resolved, type_name, FullName(), options,
                                                   std::move(handler));
  if (!options.worker_of.empty()) {
    executor_.AddTimer(std::chrono::seconds(1), [raw = server.get()] { raw->Heartbeat(); });
    logger_->info("serving {} as a worker of the pool at {}", resolved, options.worker_of);
  }
  servers_.push_back(server);
  RawServiceServer* raw = server.get();
  executor_.AddSocket(&server->Socket(), [this, raw] {
    const uint64_t errors_before = raw->Stats().errors.load() + raw->Stats().malformed.load();
    raw->Drain();
    if (raw->Stats().errors.load() + raw->Stats().malformed.load() != errors_before) {
      WarnThrottled("service:" + raw->Name(),
                    "service " + raw->Name() + " request failed: " + raw->LastError());
    }
  });
  logger_->debug("serving {} ({}) on {}", resolved, type_name, server->Endpoint());
  return server;
}

void Node::Start() {
  if (started_) return;
  params_.CheckAllDeclared();
  started_ = true;
  if (status_period_s_ > 0) {
    status_pub_ = Advertise<msgs::pb::NodeStatus>("~/status");
    executor_.AddTimer(std::chrono::duration_cast<std::chrono::nanoseconds>(
                           std::chrono::duration<double>(status_period_s_)),
                       [this] { status_pub_->Publish(MakeStatus()); });
  }
  // An `endpoints` key that names none of this node's topics or services would be ignored:
  // the topic then silently uses its default endpoint.
  std::string unknown;
  for (const auto& [key, ep] : endpoints_) {
    if (endpoint_names_used_.count(key) == 0 && endpoint_names_used_.count(Resolve(key)) == 0)
      unknown += (unknown.empty() ? "'" : ", '") + key + "'";
  }
  if (!unknown.empty()) {
    std::string names;
    for (const auto& n : endpoint_names_used_) {
      if (!n.empty() && n[0] == '/') names += " " + n;
    }
    throw StartupError("parameter 'endpoints': " + unknown + " name(s) no topic or service of "
                       "this node (its names:" + names + ")");
  }
  executor_.AddTimer(std::chrono::duration_cast<std::chrono::nanoseconds>(
                         std::chrono::duration<double>(latch_period_s_)),
                     [this] {
                       for (auto& p : publishers_) {
                         if (p->Options().latched) p->RepublishLatched();
                       }
                     });
  param_service_ = std::make_unique<ParamService>(FullName(), &params_);
  for (const auto& [name, setter] : dynamic_) param_service_->SetDynamic(name, setter);
  param_service_->Publish();
  executor_.AddTimer(std::chrono::milliseconds(250), [this] { param_service_->Poll(); });
  logger_->info("started (namespace {}, {} publishers, {} subscriptions, {} services)",
                Namespace(), publishers_.size(), subscribers_.size(), servers_.size());
}

bool Node::SpinOnce(std::chrono::nanoseconds max_wait) {
  Start();
  return executor_.SpinOnce(max_wait);
}

void Node::Spin() {
  Start();
  executor_.Spin();
  logger_->info("shutting down");
  Close();
}

void Node::Close() {
  if (closed_) return;
  closed_ = true;
  try {
    OnShutdown();
  } catch (const std::exception& e) {
    logger_->error("OnShutdown failed: {}", e.what());
  }
  if (status_pub_ && started_) {
    auto status = MakeStatus();
    status.set_alive(false);
    status_pub_->Publish(status);  // last word: subscribers see the node go away
  }
  watcher_.reset();  // stops its thread before the subscribers it posts to go away
  for (auto& s : subscribers_) executor_.RemoveSocket(&s->Socket());
  for (auto& s : servers_) executor_.RemoveSocket(&s->Socket());
  subscribers_.clear();
  servers_.clear();
  status_pub_.reset();
  param_service_.reset();
  publishers_.clear();  // sockets closed with linger 0 by their destructors (if not shared)
  logger_->flush();
}

void Node::Count(const std::string& key, uint64_t n) {
  std::lock_guard<std::mutex> lock(counters_mutex_);
  counters_[key] += n;
}

void Node::SetValue(const std::string& key, double value) {
  std::lock_guard<std::mutex> lock(counters_mutex_);
  values_[key] = value;
}

msgs::pb::NodeStatus Node::MakeStatus() const {
  msgs::pb::NodeStatus s;
  s.set_node(FullName());
  s.set_alive(true);
  s.set_uptime_s(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time_)
                     .count());
  auto& c = *s.mutable_counters();
  uint64_t published = 0, received = 0, dropped = 0, skipped = 0, malformed = 0,
           duplicates = 0, requests = 0, request_errors = 0;
  uint64_t refused_subscriptions = 0;
  for (const auto& p : publishers_) {
    published += p->Stats().published.load();
    refused_subscriptions += p->Stats().refused_subscriptions.load();
  }
  for (const auto& sub : subscribers_) {
    const auto& st = sub->Stats();
    received += st.received.load();
    dropped += st.dropped.load();
    skipped += st.skipped.load();
    malformed += st.malformed.load();
    duplicates += st.duplicates.load();
  }
  for (const auto& sv : servers_) {
    requests += sv->Stats().requests.load();
    request_errors += sv->Stats().errors.load();
    malformed += sv->Stats().malformed.load();
  }
  c["published"] = published;
  c["received"] = received;
  c["dropped"] = dropped;
  c["skipped"] = skipped;
  c["malformed"] = malformed;
  c["duplicates"] = duplicates;
  c["requests"] = requests;
  c["request_errors"] = request_errors;
  c["refused_subscriptions"] = refused_subscriptions;
  const CurveStats& curve = CurveSecurity::Stats();  // process-wide (docs/SECURITY.md)
  if (curve.accepted.load() + curve.refused_key.load() + curve.refused_handshake.load() > 0) {
    c["curve_accepted"] = curve.accepted.load();
    c["curve_refused_key"] = curve.refused_key.load();
    c["curve_refused_handshake"] = curve.refused_handshake.load();
  }
  std::lock_guard<std::mutex> lock(counters_mutex_);
  for (const auto& [k, v] : counters_) c[k] = v;
  for (const auto& [k, v] : values_) (*s.mutable_values())[k] = v;
  return s;
}

void Node::WarnThrottled(const std::string& key, const std::string& text) {
  const auto now = std::chrono::steady_clock::now();
  auto& last = last_warn_[key];
  if (last.time_since_epoch().count() != 0 && now - last < std::chrono::seconds(1)) return;
  last = now;
  logger_->warn("{}", text);
}

}  // namespace p2i::runtime
