/// @file curve_auth.h
/// @brief ZeroMQ CURVE on tcp:// endpoints: key files, the process-wide key configuration
/// ($P2I_CURVE_DIR), a ZAP handler that admits listed client keys only, and counters of refused
/// handshakes (docs/SECURITY.md).
///
/// Key directory ($P2I_CURVE_DIR, made by `p2i keygen --init DIR`):
///   self.key         this host's key pair ("public Z85" / "secret Z85" lines), mode 0600;
///                    servers (bound tcp sockets) use it as their secret key, clients as theirs
///   authorized_keys  client public keys allowed to connect here: one Z85 key per line
///                    (anything after the key is a comment; '#' lines too)
///   servers          "HOST Z85" lines: the public key of the server at tcp://HOST:...;
///                    HOST "*" matches any host
/// Without $P2I_CURVE_DIR nothing changes (plain ZeroMQ). ipc:// endpoints are never
/// encrypted: they live in a 0700 run directory (see RunDir()).
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <set>
#include <string>

#include <spdlog/logger.h>
#include <zmq.hpp>

namespace p2i::runtime {

/// Z85 text of a CURVE key pair (40 characters each).
struct CurveKeyPair {
  std::string public_z85;
  std::string secret_z85;  ///< empty for a public-only (.pub) file
};

/// True when the linked libzmq was built with CURVE (zmq_has("curve")).
bool CurveAvailable();
/// A fresh key pair; throws std::runtime_error when CURVE is unavailable.
CurveKeyPair GenerateCurveKeyPair();
/// Writes `path` ("public"/"secret" lines; mode 0600 with the secret, else 0644) atomically:
/// WriteKeyFileTmp then CommitKeyFile. Throws on IO errors, leaving no .tmp file and `path` as
/// it was.
void WriteKeyFile(const std::string& path, const CurveKeyPair& keys, bool with_secret);
/// The first half: writes and fsyncs `path`.tmp (created 0600 / 0644, never through a link) and
/// returns its name; on an error removes it and throws. Lets `p2i keygen` write a key and its
/// .pub before replacing either.
std::string WriteKeyFileTmp(const std::string& path, const CurveKeyPair& keys, bool with_secret);
/// The second half: renames `path`.tmp over `path`; on an error removes the .tmp and throws.
void CommitKeyFile(const std::string& path);
/// Reads a key file written by WriteKeyFile (or a bare Z85 public key line). Throws naming
/// the file and line on a missing/invalid key.
CurveKeyPair ReadKeyFile(const std::string& path);
/// True for 40 characters of the Z85 alphabet that decode to 32 bytes.
bool IsZ85Key(const std::string& text);

/// The keys of one process (see the file comment for the directory layout).
struct CurveConfig {
  bool enabled = false;
  std::string dir;
  CurveKeyPair self;
  std::set<std::string> authorized;            ///< client public keys (Z85)
  std::map<std::string, std::string> servers;  ///< host (or "*") -> server public key

  /// Loads DIR; throws std::runtime_error naming the missing or bad file and how to fix it.
  static CurveConfig Load(const std::string& dir);
  /// Server key for a tcp://HOST:PORT endpoint; throws naming DIR/servers when none matches.
  std::string ServerKeyFor(const std::string& endpoint) const;
};

/// Refusals and successes seen by this process's secured server sockets.
struct CurveStats {
  std::atomic<uint64_t> accepted{0};         ///< handshakes that succeeded (listed key)
  std::atomic<uint64_t> refused_key{0};      ///< ZAP said no: unlisted (or wrong) client key
  std::atomic<uint64_t> refused_handshake{0};///< plain client, wrong server key, garbage
};

/// Process-wide CURVE state. Thread-safe.
class CurveSecurity {
 public:
  /// The configuration from $P2I_CURVE_DIR (loaded on first use; throws like Load()).
  static const CurveConfig& Config();
  /// Replaces the configuration (tests; `enabled = false` turns CURVE off).
  static void Configure(CurveConfig config);
  /// Call before bind()/connect() of a socket on `endpoint`. For tcp:// endpoints with CURVE
  /// enabled: a binding socket becomes a CURVE server (self secret key, ZAP domain "p2i", the
  /// ZAP handler started, handshake failures counted by a monitor); a connecting one a CURVE
  /// client of the server key for the endpoint's host. Otherwise does nothing. Returns whether
  /// CURVE was applied. Throws std::runtime_error naming `what` when no server key is known.
  static bool Apply(zmq::socket_t& socket, const std::string& endpoint, bool bind,
                    const std::string& what);
  static const CurveStats& Stats();
  /// Where refusals are logged (a node sets its own logger; default spdlog's default logger).
  static void SetLogger(std::shared_ptr<spdlog::logger> logger);
};

}  // namespace p2i::runtime
