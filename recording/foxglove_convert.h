/// @file foxglove_convert.h
/// @brief p2i messages -> Foxglove's well-known schemas (msgs/foxglove.proto), so Foxglove
/// shows camera frames, synthetic views, calibration and the camera path in 3D.
///
/// For a p2i topic T (names below; frame = the message's header.frame_id or, for poses, the
/// pose's child_frame, "camera" if both are empty):
///   RgbdFrame : T/foxglove/rgb (RawImage rgb8), T/foxglove/depth (RawImage 16UC1, mm),
///               T/foxglove/calibration (CameraCalibration, when inline), and with a pose
///               T/foxglove/tf (FrameTransform parent -> frame: the camera trajectory)
///   View      : T/foxglove/rgb, T/foxglove/depth, T/foxglove/pose (PoseInFrame), T/foxglove/tf
///   CameraInfo: T/foxglove/calibration
///   PoseStamped: T/foxglove/pose (PoseInFrame) and T/foxglove/tf
///   PoseRequest: T/foxglove/pose (each requested pose)
/// Other types have no Foxglove counterpart (their p2i channels still carry their schema).
#pragma once

#include <string>
#include <vector>

#include <google/protobuf/descriptor.h>

#include "msgs/wire.h"

namespace p2i::recording {

struct FoxgloveMessage {
  std::string topic;                             ///< e.g. "/camera/rgbd/foxglove/rgb"
  const google::protobuf::Descriptor* schema;    ///< e.g. foxglove.RawImage
  std::string data;                              ///< serialized message
};

/// The Foxglove channels derived from a p2i topic of type `p2i_type` ("RgbdFrame", as in the
/// discovery registry): (topic suffix such as "/foxglove/rgb", schema). Empty for other types.
std::vector<std::pair<std::string, const google::protobuf::Descriptor*>> FoxgloveChannelsFor(
    const std::string& p2i_type);

/// Converts one p2i message published on `topic`. Empty for types without a counterpart and
/// for messages that fail msgs::Decode (counted there, never thrown).
std::vector<FoxgloveMessage> ToFoxglove(const std::string& topic, const msgs::WireMessage& m);

}  // namespace p2i::recording
