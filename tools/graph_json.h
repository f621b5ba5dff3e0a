/// @file graph_json.h
/// @brief Messages from the command line for `p2i topic pub` / `p2i service call`: the value is
/// YAML or JSON (ROS 2 style: `'{pose: {position: {x: 1}}}'`), read into the protobuf message of
/// the given type (field names as in msgs/p2i.proto), with the header filled in.
#pragma once

#include <memory>
#include <string>

#include <google/protobuf/message.h>

#include "msgs/codec.h"

namespace p2i::tools {

/// The MsgType named `type` ("PoseStamped", "RenderRequest", ...); throws std::invalid_argument
/// listing the known names.
msgs::pb::MsgType MsgTypeFromName(const std::string& type);

/// A message of `type` from YAML/JSON text; header.type set, header.publisher = `publisher`.
/// Throws std::invalid_argument naming the field that does not fit.
std::unique_ptr<google::protobuf::Message> MessageFromText(msgs::pb::MsgType type,
                                                           const std::string& text,
                                                           const std::string& publisher);

/// Sets header.seq, header.request_id (when `request_id` > 0) and the publish stamp.
void StampHeader(google::protobuf::Message* msg, uint64_t seq, uint64_t request_id);

}  // namespace p2i::tools
