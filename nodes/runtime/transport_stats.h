/// @file transport_stats.h
/// @brief Counters of one publisher or subscriber, readable from any thread.
#pragma once

#include <atomic>
#include <cstdint>

namespace p2i::runtime {

/// Monotonic counters; written by the socket's owner thread, read by anyone (relaxed atomics).
struct TransportStats {
  std::atomic<uint64_t> published{0};    ///< messages sent (publisher)
  std::atomic<uint64_t> bytes{0};        ///< bytes sent or received
  std::atomic<uint64_t> received{0};     ///< well-formed messages received (subscriber)
  std::atomic<uint64_t> delivered{0};    ///< handed to the callback (after decode, latest-only)
  std::atomic<uint64_t> dropped{0};      ///< sequence gaps: lost in transit (HWM or slow link)
  std::atomic<uint64_t> skipped{0};      ///< discarded on purpose by latest-only draining
  std::atomic<uint64_t> duplicates{0};   ///< same seq again (latched re-publication)
  std::atomic<uint64_t> malformed{0};    ///< bad frames/headers/topic or failed decode
  /// Publisher: subscription messages refused (a filter that is not a prefix of the topic
  /// frame: it could only match other topics, so only its memory would be kept).
  std::atomic<uint64_t> refused_subscriptions{0};
};

}  // namespace p2i::runtime
