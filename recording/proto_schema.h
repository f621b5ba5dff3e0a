/// @file proto_schema.h
/// @brief Protobuf schemas as MCAP and Foxglove want them: a serialized FileDescriptorSet of a
/// message's file and all its imports; and the p2i message type of each MsgType.
#pragma once

#include <string>

#include <google/protobuf/descriptor.h>

#include "msgs/p2i.pb.h"

namespace p2i::recording {

/// Serialized google.protobuf.FileDescriptorSet holding `type`'s file and, before it, every
/// file it imports (transitively, dependencies first).
std::string FileDescriptorSetFor(const google::protobuf::Descriptor* type);

/// The top-level p2i message of a MsgType (POSE -> p2i.msgs.pb.PoseStamped, ...); nullptr for
/// MSG_UNKNOWN or values this build does not know.
const google::protobuf::Descriptor* DescriptorOf(msgs::pb::MsgType type);

/// A message schema by its full name, e.g. "p2i.msgs.pb.RgbdFrame" or "foxglove.RawImage",
/// from the compiled-in pool; nullptr if unknown.
const google::protobuf::Descriptor* FindDescriptor(const std::string& full_name);

}  // namespace p2i::recording
