/// @file codec.h
/// @brief Encode / decode / validate every p2i message to and from its wire form.
///
/// Wire form (msgs/wire.h): [topic + '\0'][header frame][blob 0][blob 1]...; this codec deals
/// with the header frame (a serialized top-level protobuf message, see msgs/p2i.proto) and the
/// blobs. All functions are thread-safe (they share only the atomic DecodeStats counters and
/// the atomic size limit).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "msgs/decode_stats.h"
#include "msgs/image.h"
#include "msgs/p2i.pb.h"
#include "msgs/wire.h"

namespace p2i::msgs {

/// Schema version written by Encode. Decoders accept [kMinSchemaVersion, kSchemaVersion].
constexpr uint32_t kSchemaVersion = 1;
constexpr uint32_t kMinSchemaVersion = 1;
/// Largest width or height of an image blob.
constexpr uint32_t kMaxImageSide = 16384;
/// Largest number of poses in a RenderRequest / views in a RenderReply.
constexpr int kMaxBatch = 4096;
/// Relative tolerance on the quaternion norm; within it the decoder normalises.
constexpr double kQuaternionTolerance = 1e-3;
/// Default limit on WireSize() of a message a decoder accepts.
constexpr size_t kDefaultMaxMessageBytes = size_t{256} << 20;

/// Sets / reads the process-wide size limit used by every decoder (default 256 MiB).
void SetMaxMessageBytes(size_t bytes);
size_t MaxMessageBytes();

// ---- Type ids ----------------------------------------------------------------------------------

template <class T>
struct TypeTraits;  // specialised below for every message type

/// The MsgType of a C++ message type, e.g. TypeOf<pb::PoseStamped>() == pb::POSE.
template <class T>
constexpr pb::MsgType TypeOf() {
  return TypeTraits<T>::kType;
}

#define P2I_MSGS_TYPE(T, ID)                   \
  template <>                                  \
  struct TypeTraits<T> {                       \
    static constexpr pb::MsgType kType = ID;   \
  };
P2I_MSGS_TYPE(pb::PoseStamped, pb::POSE)
P2I_MSGS_TYPE(pb::CameraInfo, pb::CAMERA_INFO)
P2I_MSGS_TYPE(RgbdFrame, pb::RGBD_FRAME)
P2I_MSGS_TYPE(pb::PoseRequest, pb::POSE_REQUEST)
P2I_MSGS_TYPE(View, pb::VIEW)
P2I_MSGS_TYPE(pb::ModelVersion, pb::MODEL_VERSION)
P2I_MSGS_TYPE(pb::TrainerStatus, pb::TRAINER_STATUS)
P2I_MSGS_TYPE(pb::NodeStatus, pb::NODE_STATUS)
P2I_MSGS_TYPE(pb::RenderRequest, pb::RENDER_REQUEST)
P2I_MSGS_TYPE(pb::RenderReply, pb::RENDER_REPLY)
P2I_MSGS_TYPE(RenderReplyMsg, pb::RENDER_REPLY)
#undef P2I_MSGS_TYPE

/// "PoseStamped", "RgbdFrame", ... ("Unknown" for values outside MsgType).
const char* TypeName(pb::MsgType type);

// ---- Header access -----------------------------------------------------------------------------

inline pb::Header* MutableHeader(pb::PoseStamped& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::CameraInfo& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::PoseRequest& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::ModelVersion& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::TrainerStatus& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::NodeStatus& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::RenderRequest& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(pb::RenderReply& m) { return m.mutable_header(); }
inline pb::Header* MutableHeader(RgbdFrame& m) { return m.meta.mutable_header(); }
inline pb::Header* MutableHeader(View& m) { return m.meta.mutable_header(); }
inline pb::Header* MutableHeader(RenderReplyMsg& m) { return m.meta.mutable_header(); }

inline const pb::Header& GetHeader(const pb::PoseStamped& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::CameraInfo& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::PoseRequest& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::ModelVersion& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::TrainerStatus& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::NodeStatus& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::RenderRequest& m) { return m.header(); }
inline const pb::Header& GetHeader(const pb::RenderReply& m) { return m.header(); }
inline const pb::Header& GetHeader(const RgbdFrame& m) { return m.meta.header(); }
inline const pb::Header& GetHeader(const View& m) { return m.meta.header(); }
inline const pb::Header& GetHeader(const RenderReplyMsg& m) { return m.meta.header(); }

// ---- Encode ------------------------------------------------------------------------------------
// Encode sets header.type and header.schema_version itself; the caller sets seq, stamps,
// frame_id, request_id, publisher. For image types, the ImageInfo fields of the metadata are
// (re)written from the Image structs (step 0 becomes the packed step) and the blobs are shared,
// not copied. Encode does not validate values (the receiver does); it throws
// std::invalid_argument only for a programmer error: an Image whose `data` is null, or a
// RenderReplyMsg whose image count is neither 0 nor 2 * views.

WireMessage Encode(const pb::PoseStamped& msg);
WireMessage Encode(const pb::CameraInfo& msg);
WireMessage Encode(const pb::PoseRequest& msg);
WireMessage Encode(const pb::ModelVersion& msg);
WireMessage Encode(const pb::TrainerStatus& msg);
WireMessage Encode(const pb::NodeStatus& msg);
WireMessage Encode(const pb::RenderRequest& msg);
WireMessage Encode(const pb::RenderReply& msg);  ///< a reply without images
WireMessage Encode(const RgbdFrame& msg);
WireMessage Encode(const View& msg);
WireMessage Encode(const RenderReplyMsg& msg);

// ---- Decode ------------------------------------------------------------------------------------
// Decode validates everything (see docs/MESSAGES.md, "Validation") and returns false with a
// one-line reason "<reason class>: <field>: <what>" in *error (if error is not null) on bad
// input; it then leaves *out unchanged and counts the reason in DecodeStats::Global(). It never
// throws and never reads out of bounds. Quaternions within kQuaternionTolerance are normalised
// in *out. Decoded images share the wire's blobs (no copy).

bool Decode(const WireMessage& wire, pb::PoseStamped* out, std::string* error);
bool Decode(const WireMessage& wire, pb::CameraInfo* out, std::string* error);
bool Decode(const WireMessage& wire, pb::PoseRequest* out, std::string* error);
bool Decode(const WireMessage& wire, pb::ModelVersion* out, std::string* error);
bool Decode(const WireMessage& wire, pb::TrainerStatus* out, std::string* error);
bool Decode(const WireMessage& wire, pb::NodeStatus* out, std::string* error);
bool Decode(const WireMessage& wire, pb::RenderRequest* out, std::string* error);
/// Validates the images too (if any), then drops them.
bool Decode(const WireMessage& wire, pb::RenderReply* out, std::string* error);
bool Decode(const WireMessage& wire, RgbdFrame* out, std::string* error);
bool Decode(const WireMessage& wire, View* out, std::string* error);
bool Decode(const WireMessage& wire, RenderReplyMsg* out, std::string* error);

/// Same as Decode, also returning the reason class (kOk on success) for callers and tests that
/// need to tell reasons apart without parsing the error string.
template <class T>
bool Decode(const WireMessage& wire, T* out, std::string* error, DecodeReason* reason);

/// Parses only the header of a header frame (any type): checks that it parses and that the
/// type is known. Does not check the schema version or count anything (the transport uses it
/// to route; Decode does the full checks).
bool PeekHeader(const std::string& header_frame, pb::Header* out, std::string* error);

/// Human-readable text of any message for `p2i topic echo`: the header and fields as protobuf
/// text, each blob as "<blob N: W x H ENC, B bytes>", and "INVALID: <reason>" if the message
/// would be rejected. Never throws on bad input; does not count in DecodeStats.
std::string DebugString(const WireMessage& wire);

/// An empty protobuf message of the top-level type `type` (the header frame's schema), or null
/// for an unknown type. For generic tools (DebugString, fuzzers) that handle any message.
std::unique_ptr<google::protobuf::Message> NewMessage(pb::MsgType type);

/// Validation of a pose on its own (also used by the decoders): finite position, orientation
/// present with norm within kQuaternionTolerance of 1; normalises the orientation. `field`
/// names the pose in *error.
bool ValidatePose(pb::Pose* pose, const std::string& field, std::string* error);

}  // namespace p2i::msgs
