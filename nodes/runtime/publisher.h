/// @file publisher.h
/// @brief Typed publisher: stamps the header (seq, publish time, publisher) and encodes.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "msgs/codec.h"
#include "nodes/runtime/raw_publisher.h"

namespace p2i::runtime {

/// Nanoseconds since the Unix epoch (system clock), the unit of every header stamp.
inline int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// Publishes messages of type T (any type msgs::Encode accepts) on one topic.
/// Publish() sets header.seq (per publisher, 1, 2, ...), header.publish_stamp_ns and
/// header.publisher (the node's full name); the caller sets capture stamp and frame_id.
/// Thread-safety: as RawPublisher (Publish may be called from any thread).
template <class T>
class Publisher {
 public:
  Publisher(std::shared_ptr<RawPublisher> raw, std::string node_name)
      : raw_(std::move(raw)), node_name_(std::move(node_name)) {}

  void Publish(const T& msg) {
    T copy = msg;  // images are shared blobs: this copies metadata only
    msgs::pb::Header* h = msgs::MutableHeader(copy);
    h->set_seq(raw_->NextSeq());
    h->set_publish_stamp_ns(NowNs());
    h->set_publisher(node_name_);
    raw_->Publish(msgs::Encode(copy));
  }

  RawPublisher& Raw() { return *raw_; }
  const std::string& Topic() const { return raw_->Topic(); }

 private:
  std::shared_ptr<RawPublisher> raw_;
  std::string node_name_;
};

}  // namespace p2i::runtime
