/// @file service_client.h
/// @brief Typed service client over RawServiceClient (Lazy Pirate).
#pragma once

#include <memory>
#include <string>

#include "msgs/codec.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_service.h"

namespace p2i::runtime {

/// Calls a service with request type Req and reply type Rep. Call() writes the request id and
/// publish stamp into the request header, retries as configured (see RawServiceClient) and
/// decodes the reply (a reply that does not decode, or whose header.request_id is set and
/// differs, is a failure with the reason in `error`).
/// Thread-safety: one owner thread (the caller of Call()); use one client per thread.
template <class Req, class Rep>
class ServiceClient {
 public:
  ServiceClient(std::string resolved_name, std::string node_name, ServiceClientOptions options)
      : raw_(std::move(resolved_name), std::move(options)), node_name_(std::move(node_name)) {}

  bool Call(const Req& request, Rep* reply, std::string* error) {
    Req copy = request;
    msgs::pb::Header* h = msgs::MutableHeader(copy);
    const uint64_t id = raw_.NextRequestId();
    h->set_request_id(id);
    h->set_seq(id);
    h->set_publish_stamp_ns(NowNs());
    h->set_publisher(node_name_);
    msgs::WireMessage wire_reply;
    if (!raw_.Call(msgs::Encode(copy), &wire_reply, error)) return false;
    std::string why;
    if (!msgs::Decode(wire_reply, reply, &why)) {
      *error = "service '" + raw_.Name() + "': undecodable reply: " + why;
      return false;
    }
    const uint64_t got = msgs::GetHeader(*reply).request_id();
    if (got != 0 && got != id) {
      *error = "service '" + raw_.Name() + "': reply header carries request id " +
               std::to_string(got) + ", expected " + std::to_string(id);
      return false;
    }
    return true;
  }

  RawServiceClient& Raw() { return raw_; }

 private:
  RawServiceClient raw_;
  std::string node_name_;
};

}  // namespace p2i::runtime
