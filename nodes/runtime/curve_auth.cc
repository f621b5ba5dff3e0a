/// @file curve_auth.cc
/// @brief CURVE key files, key directory, ZAP handler thread and handshake monitor thread.
#include "nodes/runtime/curve_auth.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cerrno>
#include <cstring>
#include <functional>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include "nodes/runtime/zmq_context.h"

namespace p2i::runtime {
namespace {

constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";
constexpr const char* kZapDomain = "p2i";

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::string Z85Of(const std::string& binary32) {
  char out[41];
  zmq_z85_encode(out, reinterpret_cast<const uint8_t*>(binary32.data()), 32);
  return std::string(out, 40);
}

/// Logs at most once per second per key (a flood of bad peers must not flood the log).
std::mutex g_log_mutex;
std::shared_ptr<spdlog::logger> g_logger;  // guarded by g_log_mutex

void WarnThrottled(const std::string& key, const std::string& text) {
  static std::map<std::string, std::chrono::steady_clock::time_point> last;
  const auto now = std::chrono::steady_clock::now();
  std::shared_ptr<spdlog::logger> logger;
  {
    std::lock_guard<std::mutex> lock(g_log_mutex);
    auto it = last.find(key);
    if (it != last.end() && now - it->second < std::chrono::seconds(1)) return;
    last[key] = now;
    logger = g_logger ? g_logger : spdlog::default_logger();
  }
  logger->warn("{}", text);
  logger->flush();
}

struct State {
  std::mutex mutex;
  bool loaded = false;
  CurveConfig config;
  CurveStats stats;
  bool zap_started = false;
  // Monitor PAIR sockets connected by Apply() and handed to the monitor thread.
  std::vector<std::unique_ptr<zmq::socket_t>> pending_monitors;
  bool monitor_started = false;
  int monitor_seq = 0;
};

State& S() {
  static State* s = new State();  // leaked: the threads below live until the process exits
  return *s;
}

// ZAP (RFC 27): REP socket on inproc://zeromq.zap.01; admits CURVE clients with listed keys.
void ZapLoop(zmq::socket_t* socket) {
  while (true) {
    std::vector<zmq::message_t> frames;
    zmq::message_t m;
    try {
      if (!socket->recv(m, zmq::recv_flags::none)) continue;
      frames.push_back(std::move(m));
      while (frames.back().more()) {
        zmq::message_t next;
        (void)socket->recv(next, zmq::recv_flags::none);
        frames.push_back(std::move(next));
      }
    } catch (const zmq::error_t&) {
      continue;  // EINTR
    }
    std::string status = "400", text = "malformed ZAP request", user;
    std::string version = frames.size() > 0 ? frames[0].to_string() : "";
    std::string request_id = frames.size() > 1 ? frames[1].to_string() : "";
    if (frames.size() >= 6) {
      const std::string address = frames[3].to_string();
      const std::string mechanism = frames[5].to_string();
      if (mechanism == "CURVE" && frames.size() >= 7 && frames[6].size() == 32) {
        const std::string key = Z85Of(frames[6].to_string());
        bool ok = false;
        {
          std::lock_guard<std::mutex> lock(S().mutex);
          ok = S().config.authorized.count(key) > 0;
        }
        if (ok) {
          status = "200";
          text = "OK";
          user = key;
        } else {
          text = "client key not in authorized_keys";
          S().stats.refused_key.fetch_add(1);
          WarnThrottled("zap:" + address,
                        "CURVE: refused client " + address + " with unlisted key " + key +
                            " (add it to " + S().config.dir + "/authorized_keys to admit it; " +
                            std::to_string(S().stats.refused_key.load()) + " refused so far)");
        }
      } else {
        text = "mechanism " + mechanism + " not allowed";
        S().stats.refused_key.fetch_add(1);
        WarnThrottled("zap:" + address, "CURVE: refused client " + address + " (mechanism " +
                                            mechanism + ")");
      }
    }
    const std::vector<std::string> reply = {version.empty() ? "1.0" : version, request_id,
                                            status, text, user, ""};
    try {
      for (size_t i = 0; i < reply.size(); ++i)
        socket->send(zmq::buffer(reply[i]),
                     i + 1 < reply.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
    } catch (const zmq::error_t&) {
    }
  }
}

void StartZapLocked(State& s) {
  if (s.zap_started) return;
  auto* socket = new zmq::socket_t(ZmqContext(), zmq::socket_type::rep);
  socket->set(zmq::sockopt::linger, 0);
  socket->bind(kZapEndpoint);  // bound before any CURVE server binds (Apply holds the lock)
  std::thread(ZapLoop, socket).detach();
  s.zap_started = true;
}

std::string HandshakeReason(uint16_t event, uint32_t value) {
  if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH)
    return "client key refused (ZAP status " + std::to_string(value) + ")";
  if (event == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) {
    switch (value) {
      case ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH:
        return "plain client (no CURVE, or another mechanism)";
      case ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC:
        return "cannot decrypt the client's HELLO (client has a wrong server key)";
      default: {
        char buf[32];
        std::snprintf(buf, sizeof(buf), "0x%08x", value);
        return std::string("malformed handshake (protocol error ") + buf + ")";
      }
    }
  }
  // libzmq gives no reason when the peer hangs up mid-handshake: a plain client that read our
  // CURVE greeting first does exactly that (and does not come back), as does a dropped link.
  return "malformed handshake or one the peer abandoned (no detail: e.g. a plain client that hung "
         "up on the CURVE greeting, or a dropped connection)";
}

void MonitorLoop() {
  std::vector<std::unique_ptr<zmq::socket_t>> sockets;
  while (true) {
    {
      std::lock_guard<std::mutex> lock(S().mutex);
      for (auto& p : S().pending_monitors) sockets.push_back(std::move(p));
      S().pending_monitors.clear();
    }
    if (sockets.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    std::vector<zmq::pollitem_t> items;
    for (auto& s : sockets) items.push_back({s->handle(), 0, ZMQ_POLLIN, 0});
    try {
      zmq::poll(items.data(), items.size(), std::chrono::milliseconds(20));
    } catch (const zmq::error_t&) {
      continue;
    }
    for (size_t i = 0; i < items.size(); ++i) {
      if (!(items[i].revents & ZMQ_POLLIN)) continue;
      zmq::message_t head, addr;
      if (!sockets[i]->recv(head, zmq::recv_flags::dontwait)) continue;
      if (head.more()) (void)sockets[i]->recv(addr, zmq::recv_flags::dontwait);
      if (head.size() < 6) continue;
      uint16_t event;
      uint32_t value;
      std::memcpy(&event, head.data(), 2);
      std::memcpy(&value, static_cast<const char*>(head.data()) + 2, 4);
      const std::string where = addr.to_string();
      if (event == ZMQ_EVENT_MONITOR_STOPPED) {
        sockets[i].reset();
        continue;
      }
      if (event == ZMQ_EVENT_HANDSHAKE_SUCCEEDED) {
        S().stats.accepted.fetch_add(1);
        continue;
      }
      if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) continue;  // counted by the ZAP handler
      S().stats.refused_handshake.fetch_add(1);
      const std::string reason = HandshakeReason(event, value);
      WarnThrottled("mon:" + where + reason,
                    "CURVE: refused a connection on " + where + ": " + reason + " (" +
                        std::to_string(S().stats.refused_handshake.load()) +
                        " refused handshakes so far)");
    }
    std::vector<std::unique_ptr<zmq::socket_t>> alive;
    for (auto& s : sockets)
      if (s) alive.push_back(std::move(s));
    sockets.swap(alive);
  }
}

// tcp://HOST:PORT -> HOST (brackets of IPv6 removed).
std::string HostOf(const std::string& endpoint) {
  std::string rest = endpoint.substr(endpoint.find("://") + 3);
  if (!rest.empty() && rest[0] == '[') return rest.substr(1, rest.find(']') - 1);
  const auto colon = rest.rfind(':');
  return colon == std::string::npos ? rest : rest.substr(0, colon);
}

}  // namespace

bool CurveAvailable() { return zmq_has("curve") != 0; }

bool IsZ85Key(const std::string& text) {
  if (text.size() != 40) return false;
  uint8_t out[32];
  return zmq_z85_decode(out, text.c_str()) != nullptr;
}

CurveKeyPair GenerateCurveKeyPair() {
  if (!CurveAvailable())
    throw std::runtime_error("this libzmq was built without CURVE (zmq_has(\"curve\") is 0); "
                             "install Debian's libzmq5");
  char pub[41], sec[41];
  if (zmq_curve_keypair(pub, sec) != 0)
    throw std::runtime_error(std::string("zmq_curve_keypair failed: ") + zmq_strerror(zmq_errno()));
  return {std::string(pub, 40), std::string(sec, 40)};
}

void WriteKeyFile(const std::string& path, const CurveKeyPair& keys, bool with_secret) {
  WriteKeyFileTmp(path, keys, with_secret);
  CommitKeyFile(path);
}

std::string WriteKeyFileTmp(const std::string& path, const CurveKeyPair& keys, bool with_secret) {
  const std::string tmp = path + ".tmp";
  ::unlink(tmp.c_str());  // a leftover of an interrupted run (O_EXCL below refuses links)
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC,
                        with_secret ? 0600 : 0644);
  if (fd < 0)
    throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(errno) +
                             " (check the folder exists and is writable)");
  ::fchmod(fd, with_secret ? 0600 : 0644);  // whatever the umask
  std::string text = std::string("# p2i CURVE ") + (with_secret ? "key pair" : "public key") +
                     ", made by `p2i keygen`" +
                     (with_secret ? " (secret: keep this file private)" : "") + "\npublic " +
                     keys.public_z85 + "\n";
  if (with_secret) text += "secret " + keys.secret_z85 + "\n";
  bool ok = true;
  for (size_t done = 0; ok && done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) done += static_cast<size_t>(n);
  }
  const int err = ok ? 0 : errno;
  ok = ok && ::fsync(fd) == 0;
  ok = ::close(fd) == 0 && ok;
  if (!ok) {
    ::unlink(tmp.c_str());  // never leave a half-written key behind
    throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(err ? err : errno));
  }
  return tmp;
}

void CommitKeyFile(const std::string& path) {
  const std::string tmp = path + ".tmp";
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot replace " + path + ": " + std::strerror(err));
  }
}

CurveKeyPair ReadKeyFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read key file " + path);
  CurveKeyPair k;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    line = Trim(line);
    if (line.empty() || (line[0] == '#' && !IsZ85Key(line.substr(0, 40)))) continue;
    std::istringstream ss(line);
    std::string a, b;
    ss >> a >> b;
    std::string* dst = nullptr;
    std::string key;
    if (a == "public") dst = &k.public_z85, key = b;
    else if (a == "secret") dst = &k.secret_z85, key = b;
    else if (IsZ85Key(a)) dst = &k.public_z85, key = a;
    if (!dst || !IsZ85Key(key))
      throw std::runtime_error(path + ":" + std::to_string(n) +
                               ": expected 'public Z85KEY' or 'secret Z85KEY' (40 Z85 "
                               "characters; make keys with `p2i keygen`)");
    *dst = key;
  }
  if (k.public_z85.empty()) throw std::runtime_error(path + ": no 'public' key line");
  if (!k.secret_z85.empty()) {
    char pub[41];
    if (zmq_curve_public(pub, k.secret_z85.c_str()) != 0 || k.public_z85 != std::string(pub, 40))
      throw std::runtime_error(path + ": the public key does not belong to the secret key");
  }
  return k;
}

CurveConfig CurveConfig::Load(const std::string& dir) {
  CurveConfig c;
  c.dir = dir;
  if (!CurveAvailable())
    throw std::runtime_error("P2I_CURVE_DIR=" + dir + " asks for CURVE, but this libzmq has no "
                             "CURVE support (zmq_has(\"curve\") is 0)");
  const std::string self = dir + "/self.key";
  struct stat st {};
  if (::stat(self.c_str(), &st) != 0)
    throw std::runtime_error("CURVE key directory " + dir + " has no self.key: run `p2i keygen "
                             "--init " + dir + "` (or copy a key pair made by `p2i keygen` there)");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%o", static_cast<unsigned>(st.st_mode & 0777));
    throw std::runtime_error(self + " is readable by others (mode " + mode + "): chmod 600 " +
                             self);
  }
  c.self = ReadKeyFile(self);
  if (c.self.secret_z85.empty()) throw std::runtime_error(self + ": no 'secret' key line");
  const auto read_lines = [&](const std::string& name, const std::function<void(
                                                           const std::string&, int)>& fn) {
    const std::string path = dir + "/" + name;
    std::ifstream in(path);
    if (!in)
      throw std::runtime_error("CURVE key directory " + dir + " has no " + name +
                               ": see docs/SECURITY.md (`p2i keygen --init DIR` makes one)");
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      line = Trim(line);
      // '#' starts a comment, unless the line starts with a key ('#' is a Z85 character).
      if (line.empty() || (line[0] == '#' && !IsZ85Key(line.substr(0, 40)))) continue;
      fn(line, n);
    }
  };
  read_lines("authorized_keys", [&](const std::string& line, int n) {
    std::istringstream ss(line);
    std::string key;
    ss >> key;
    if (key == "public") ss >> key;
    if (!IsZ85Key(key))
      throw std::runtime_error(dir + "/authorized_keys:" + std::to_string(n) +
                               ": not a Z85 public key (40 characters from `p2i keygen`)");
    c.authorized.insert(key);
  });
  read_lines("servers", [&](const std::string& line, int n) {
    std::istringstream ss(line);
    std::string host, key;
    ss >> host >> key;
    if (host.empty() || !IsZ85Key(key))
      throw std::runtime_error(dir + "/servers:" + std::to_string(n) +
                               ": expected 'HOST Z85KEY' (HOST as in tcp://HOST:PORT, or *)");
    c.servers[host] = key;
  });
  c.enabled = true;
  return c;
}

std::string CurveConfig::ServerKeyFor(const std::string& endpoint) const {
  const std::string host = HostOf(endpoint);
  auto it = servers.find(host);
  if (it == servers.end()) it = servers.find("*");
  if (it == servers.end())
    throw std::runtime_error("no CURVE server key for host '" + host + "' (endpoint " + endpoint +
                             "): add a line '" + host + " PUBLICKEY' to " + dir + "/servers");
  return it->second;
}

const CurveConfig& CurveSecurity::Config() {
  State& s = S();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (!s.loaded) {
    const char* env = std::getenv("P2I_CURVE_DIR");
    if (env && *env) s.config = CurveConfig::Load(env);
    s.loaded = true;
  }
  return s.config;
}

void CurveSecurity::Configure(CurveConfig config) {
  State& s = S();
  std::lock_guard<std::mutex> lock(s.mutex);
  s.config = std::move(config);
  s.loaded = true;
}

const CurveStats& CurveSecurity::Stats() { return S().stats; }

void CurveSecurity::SetLogger(std::shared_ptr<spdlog::logger> logger) {
  std::lock_guard<std::mutex> lock(g_log_mutex);
  g_logger = std::move(logger);
}

bool CurveSecurity::Apply(zmq::socket_t& socket, const std::string& endpoint, bool bind,
                          const std::string& what) {
  if (endpoint.rfind("tcp://", 0) != 0) return false;
  const CurveConfig& c = Config();
  if (!c.enabled) return false;
  State& s = S();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (bind) {
    StartZapLocked(s);
    socket.set(zmq::sockopt::curve_server, true);
    socket.set(zmq::sockopt::curve_secretkey, s.config.self.secret_z85);
    socket.set(zmq::sockopt::zap_domain, kZapDomain);
    const std::string mon = "inproc://p2i-curve-monitor-" + std::to_string(getpid()) + "-" +
                            std::to_string(s.monitor_seq++);
    if (zmq_socket_monitor(socket.handle(), mon.c_str(),
                           ZMQ_EVENT_HANDSHAKE_SUCCEEDED | ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL |
                               ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                               ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_MONITOR_STOPPED) == 0) {
      auto pair = std::make_unique<zmq::socket_t>(ZmqContext(), zmq::socket_type::pair);
      pair->set(zmq::sockopt::linger, 0);
      pair->connect(mon);
      s.pending_monitors.push_back(std::move(pair));
      if (!s.monitor_started) {
        std::thread(MonitorLoop).detach();
        s.monitor_started = true;
      }
    }
  } else {
    std::string server_key;
    try {
      server_key = s.config.ServerKeyFor(endpoint);
    } catch (const std::exception& e) {
      throw std::runtime_error(what + ": " + e.what());
    }
    socket.set(zmq::sockopt::curve_serverkey, server_key);
    socket.set(zmq::sockopt::curve_publickey, s.config.self.public_z85);
    socket.set(zmq::sockopt::curve_secretkey, s.config.self.secret_z85);
  }
  return true;
}

}  // namespace p2i::runtime
