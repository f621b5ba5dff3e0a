/// @file recorder.h
/// @brief Records p2i topics into an MCAP file (`p2i record`): each topic a protobuf channel
/// with its p2i.proto schema as a FileDescriptorSet, pixels inline (ImageInfo.data), log time =
/// reception time; optionally Foxglove channels beside them.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "nodes/runtime/raw_subscriber.h"
#include "recording/mcap_writer.h"

namespace p2i::recording {

struct RecorderOptions {
  std::string output;               ///< FILE.mcap (required)
  std::vector<std::string> topics;  ///< resolved topic names to record...
  bool all = false;                 ///< ...or every topic found in the discovery registry
  bool foxglove = false;            ///< also write Foxglove-schema channels (foxglove_convert.h)
  bool overwrite = false;           ///< replace an existing output file
  double discovery_period_s = 0.5;  ///< how often the registry is re-read (new topics/endpoints)
  /// Receive queue per topic in messages (ZeroMQ RCVHWM); a full queue drops (counted).
  int queue_messages = 1000;
  McapWriterOptions mcap;
  /// Throws std::invalid_argument naming the option and how to fix it.
  void Validate() const;
};

/// Per-topic counters (what `p2i record` prints at the end).
struct TopicStats {
  std::string type;       ///< schema name, "" until the first message
  uint64_t messages = 0;
  uint64_t bytes = 0;     ///< serialized sizes written
  uint64_t dropped = 0;   ///< sequence gaps seen by the subscriber (lost before us)
  uint64_t malformed = 0; ///< unparsable or unknown-type messages, not written
};

/// Single-threaded: Start(), then SpinOnce() in a loop, then Stop(). Not thread-safe.
class Recorder {
 public:
  explicit Recorder(RecorderOptions options);
  ~Recorder();

  /// Opens the output (throws std::runtime_error naming the file) and subscribes.
  void Start();
  /// Waits up to `max_wait` for messages and writes what arrived; re-reads the registry every
  /// discovery_period_s. Returns the number of messages written.
  int SpinOnce(std::chrono::milliseconds max_wait);
  /// Closes the file (last chunk, summary, footer).
  void Stop();

  const std::map<std::string, TopicStats>& Stats() const { return stats_; }
  uint64_t MessagesWritten() const { return writer_.MessageCount(); }
  uint64_t BytesWritten() const { return writer_.BytesWritten(); }
  const std::string& LastError() const { return last_error_; }

 private:
  struct Topic {
    std::unique_ptr<runtime::RawSubscriber> sub;
    std::set<std::string> endpoints;
    uint16_t channel = 0;
    uint32_t sequence = 0;
    uint64_t unwritable = 0;  // failed InlineBlobs / unknown type
  };
  void Discover();
  void Subscribe(const std::string& topic, const std::vector<std::string>& endpoints);
  void Write(const std::string& topic, Topic* t, const msgs::WireMessage& m,
             const msgs::pb::Header& h, uint64_t log_time);
  uint16_t ChannelFor(const std::string& topic, const google::protobuf::Descriptor* d,
                      const std::map<std::string, std::string>& metadata);

  RecorderOptions options_;
  McapWriter writer_;
  std::map<std::string, Topic> topics_;
  std::map<std::string, TopicStats> stats_;
  std::map<std::string, uint16_t> schema_ids_;              // full name -> schema id
  std::map<std::string, uint16_t> extra_channels_;          // foxglove topic -> channel
  std::map<std::string, uint32_t> extra_sequence_;
  std::chrono::steady_clock::time_point next_discovery_;
  std::string last_error_;
};

}  // namespace p2i::recording
