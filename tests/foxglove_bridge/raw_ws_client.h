/// @file raw_ws_client.h
/// @brief A minimal RFC 6455 WebSocket client over a blocking TCP socket, so tests and
/// bench/recording_bench control every byte (handshake, masked frames, a client that stops
/// reading). Not a general-purpose client: text/binary frames, no fragmentation.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

namespace p2i::testing {

using nlohmann::json;

/// Minimal RFC 6455 client over a blocking socket.
class RawWs {
 public:
  explicit RawWs(int port) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ok_ = connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawWs() { close(fd_); }
  /// Returns the HTTP response head.
  std::string Handshake(const std::string& protocol) {
    std::string req = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
                      "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                      "Sec-WebSocket-Version: 13\r\n";
    if (!protocol.empty()) req += "Sec-WebSocket-Protocol: " + protocol + "\r\n";
    req += "\r\n";
    Send(req);
    std::string head;
    char c;
    while (head.find("\r\n\r\n") == std::string::npos && Wait(3000) && recv(fd_, &c, 1, 0) == 1)
      head += c;
    return head;
  }
  void SendFrame(uint8_t opcode, const std::string& payload) {
    std::string f;
    f += static_cast<char>(0x80 | opcode);
    const size_t n = payload.size();
    if (n < 126) {
      f += static_cast<char>(0x80 | n);
    } else {
      f += static_cast<char>(0x80 | 126);
      f += static_cast<char>(n >> 8);
      f += static_cast<char>(n & 0xff);
    }
    const char mask[4] = {0x12, 0x34, 0x56, 0x78};
    f.append(mask, 4);
    for (size_t i = 0; i < n; ++i) f += static_cast<char>(payload[i] ^ mask[i % 4]);
    Send(f);
  }
  /// Next frame; false on timeout / close.
  bool ReadFrame(uint8_t* opcode, std::string* payload, int timeout_ms = 3000) {
    uint8_t h[2];
    if (!ReadN(h, 2, timeout_ms)) return false;
    // Once a frame has begun, give its rest time: giving up mid-frame would leave the stream
    // out of step (the next "header" read from the middle of a payload).
    timeout_ms = std::max(timeout_ms, 10000);
    *opcode = h[0] & 0x0f;
    uint64_t n = h[1] & 0x7f;
    if (n == 126) {
      uint8_t e[2];
      if (!ReadN(e, 2, timeout_ms)) return false;
      n = (uint64_t(e[0]) << 8) | e[1];
    } else if (n == 127) {
      uint8_t e[8];
      if (!ReadN(e, 8, timeout_ms)) return false;
      n = 0;
      for (int i = 0; i < 8; ++i) n = (n << 8) | e[i];
    }
    payload->resize(n);
    return n == 0 || ReadN(reinterpret_cast<uint8_t*>(payload->data()), n, timeout_ms);
  }
  /// Reads frames until `pred` accepts a text frame's JSON (other frames are skipped).
  json WaitText(const std::function<bool(const json&)>& pred) {
    uint8_t op;
    std::string p;
    for (int i = 0; i < 500 && ReadFrame(&op, &p); ++i) {
      if (op != 1) continue;
      json j = json::parse(p, nullptr, false);
      if (!j.is_discarded() && pred(j)) return j;
    }
    return json();
  }
  bool ok() const { return ok_; }
  void ShrinkReceiveBuffer() {
    int v = 4096;
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &v, sizeof v);
  }

 private:
  bool Wait(int ms) {
    pollfd p{fd_, POLLIN, 0};
    return poll(&p, 1, ms) == 1;
  }
  bool ReadN(uint8_t* dst, size_t n, int timeout_ms) {
    size_t got = 0;
    while (got < n) {
      if (!Wait(timeout_ms)) return false;
      const ssize_t r = recv(fd_, dst + got, n - got, 0);
      if (r <= 0) return false;
      got += static_cast<size_t>(r);
    }
    return true;
  }
  void Send(const std::string& s) { (void)!::send(fd_, s.data(), s.size(), MSG_NOSIGNAL); }
  int fd_ = -1;
  bool ok_ = false;
};

}  // namespace p2i::testing
