/// @file codec.cc
/// @brief Encoders and validating decoders of every p2i message.
#include "msgs/codec.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/message.h>
#include <google/protobuf/stubs/logging.h>

#include <atomic>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace p2i::msgs {
namespace {

namespace gpb = google::protobuf;

std::atomic<size_t> g_max_message_bytes{kDefaultMaxMessageBytes};

/// The first reason a message was rejected.
struct Failure {
  DecodeReason reason = DecodeReason::kOk;
  std::string text;
};

bool Reject(Failure* f, DecodeReason reason, const std::string& text) {
  f->reason = reason;
  f->text = std::string(DecodeReasonName(reason)) + ": " + text;
  return false;
}

std::string Join(const std::string& path, const std::string& name) {
  return path.empty() ? name : path + "." + name;
}

std::string Num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// ---- Generic checks ---------------------------------------------------------------------------

/// Every float/double field anywhere in `m` (nested messages, repeated fields, map values)
/// must be finite. Recursion depth is bounded by the schema (no recursive messages). The path
/// of the offending field is only built on failure (this runs on every message).
bool FindNonFinite(const gpb::Message& m, std::string* path, double* value) {
  const gpb::Reflection* refl = m.GetReflection();
  std::vector<const gpb::FieldDescriptor*> fields;
  refl->ListFields(m, &fields);
  for (const gpb::FieldDescriptor* fd : fields) {
    const int n = fd->is_repeated() ? refl->FieldSize(m, fd) : 1;
    for (int i = 0; i < n; ++i) {
      double v = 0;
      switch (fd->cpp_type()) {
        case gpb::FieldDescriptor::CPPTYPE_DOUBLE:
          v = fd->is_repeated() ? refl->GetRepeatedDouble(m, fd, i) : refl->GetDouble(m, fd);
          break;
        case gpb::FieldDescriptor::CPPTYPE_FLOAT:
          v = fd->is_repeated() ? refl->GetRepeatedFloat(m, fd, i) : refl->GetFloat(m, fd);
          break;
        case gpb::FieldDescriptor::CPPTYPE_MESSAGE: {
          const gpb::Message& sub =
              fd->is_repeated() ? refl->GetRepeatedMessage(m, fd, i) : refl->GetMessage(m, fd);
          if (FindNonFinite(sub, path, value)) {
            *path = fd->name() + (fd->is_repeated() ? "[" + std::to_string(i) + "]" : "") + "." +
                    *path;
            return true;
          }
          continue;
        }
        default:
          continue;
      }
      if (!std::isfinite(v)) {
        *path = fd->name() + (fd->is_repeated() ? "[" + std::to_string(i) + "]" : "");
        *value = v;
        return true;
      }
    }
  }
  return false;
}

bool CheckFinite(const gpb::Message& m, Failure* f) {
  std::string path;
  double value = 0;
  if (!FindNonFinite(m, &path, &value)) return true;
  return Reject(f, DecodeReason::kNonFinite, path + " is " + Num(value));
}

bool CheckPose(pb::Pose* pose, const std::string& field, Failure* f) {
  const auto& p = pose->position();
  if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
    return Reject(f, DecodeReason::kNonFinite, field + ".position is not finite");
  }
  if (!pose->has_orientation()) {
    return Reject(f, DecodeReason::kBadQuaternion,
                  field + ".orientation is missing (send a unit quaternion)");
  }
  auto* q = pose->mutable_orientation();
  if (!std::isfinite(q->x()) || !std::isfinite(q->y()) || !std::isfinite(q->z()) ||
      !std::isfinite(q->w())) {
    return Reject(f, DecodeReason::kNonFinite, field + ".orientation is not finite");
  }
  const double norm =
      std::sqrt(q->x() * q->x() + q->y() * q->y() + q->z() * q->z() + q->w() * q->w());
  if (!(std::fabs(norm - 1.0) <= kQuaternionTolerance)) {
    return Reject(f, DecodeReason::kBadQuaternion,
                  field + ".orientation has norm " + Num(norm) + ", off by more than " +
                      Num(kQuaternionTolerance) + " (send a unit quaternion)");
  }
  q->set_x(q->x() / norm);
  q->set_y(q->y() / norm);
  q->set_z(q->z() / norm);
  q->set_w(q->w() / norm);
  return true;
}

/// For messages whose pose is required (a template, not has_pose() and mutable_pose() as two
/// arguments: mutable_pose() would create the pose before has_pose() is evaluated).
template <class M>
bool RequirePose(M* m, const std::string& field, Failure* f) {
  if (!m->has_pose()) return Reject(f, DecodeReason::kBadValue, field + " is missing");
  return CheckPose(m->mutable_pose(), field, f);
}

bool CheckCameraInfo(const pb::CameraInfo& c, const std::string& path, Failure* f) {
  auto field = [&](const char* n) { return Join(path, n); };
  if (c.width() == 0 || c.width() > kMaxImageSide || c.height() == 0 ||
      c.height() > kMaxImageSide) {
    return Reject(f, DecodeReason::kBadValue,
                  field("width/height") + " is " + std::to_string(c.width()) + " x " +
                      std::to_string(c.height()) + ", must be 1.." +
                      std::to_string(kMaxImageSide));
  }
  if (c.k_size() != 9) {
    return Reject(f, DecodeReason::kBadValue,
                  field("k") + " has " + std::to_string(c.k_size()) + " values, expected 9");
  }
  if (!(c.k(0) > 0) || !(c.k(4) > 0)) {
    return Reject(f, DecodeReason::kBadValue,
                  field("k") + ": focal lengths fx=" + Num(c.k(0)) + " fy=" + Num(c.k(4)) +
                      " must be > 0");
  }
  if (c.r_size() != 0 && c.r_size() != 9) {
    return Reject(f, DecodeReason::kBadValue,
                  field("r") + " has " + std::to_string(c.r_size()) + " values, expected 9 or 0");
  }
  if (c.p_size() != 0 && c.p_size() != 12) {
    return Reject(f, DecodeReason::kBadValue,
                  field("p") + " has " + std::to_string(c.p_size()) +
                      " values, expected 12 or 0");
  }
  if (c.d_size() > 16) {
    return Reject(f, DecodeReason::kBadValue,
                  field("d") + " has " + std::to_string(c.d_size()) + " values, at most 16");
  }
  return true;
}

bool CheckUnit(double v, const std::string& field, Failure* f) {
  if (!(v >= 0.0 && v <= 1.0)) {  // NaN fails too
    return Reject(f, DecodeReason::kBadValue, field + " is " + Num(v) + ", must be in [0, 1]");
  }
  return true;
}

// The optional geometry fields of ViewMeta and View (fusion's observed fraction and keyframe
// angle): checked when present.
template <class M>
bool CheckGeometry(const M& m, const std::string& prefix, Failure* f) {
  if (m.has_observed_fraction() && !CheckUnit(m.observed_fraction(), prefix + "observed_fraction", f))
    return false;
  if (m.has_keyframe_angle_deg() && !(m.keyframe_angle_deg() >= 0.0 && m.keyframe_angle_deg() <= 180.0)) {
    return Reject(f, DecodeReason::kBadValue, prefix + "keyframe_angle_deg is " +
                                                  Num(m.keyframe_angle_deg()) +
                                                  ", must be in [0, 180] degrees");
  }
  return true;
}

bool CheckNonNegative(int64_t v, const std::string& field, Failure* f) {
  if (v < 0) {
    return Reject(f, DecodeReason::kBadValue, field + " is " + std::to_string(v) + ", must be >= 0");
  }
  return true;
}

// ---- Images ------------------------------------------------------------------------------------

/// Tracks which blob frames are referenced by the metadata.
class BlobRefs {
 public:
  explicit BlobRefs(const WireMessage& wire) : wire_(wire), used_(wire.blobs.size(), false) {}

  /// Checks `info` (encoding one of `allowed`, geometry, its blob) and fills `out`.
  bool Take(const pb::ImageInfo& info, const std::string& field,
            std::initializer_list<Encoding> allowed, Image* out, Failure* f) {
    bool ok_encoding = false;
    std::string names;
    for (Encoding e : allowed) {
      ok_encoding = ok_encoding || info.encoding() == e;
      names += (names.empty() ? "" : " or ") + std::string(EncodingName(e));
    }
    if (!ok_encoding) {
      return Reject(f, DecodeReason::kBadImage,
                    field + ".encoding is " + EncodingName(info.encoding()) + ", expected " + names);
    }
    if (info.width() == 0 || info.width() > kMaxImageSide || info.height() == 0 ||
        info.height() > kMaxImageSide) {
      return Reject(f, DecodeReason::kBadImage,
                    field + " is " + std::to_string(info.width()) + " x " +
                        std::to_string(info.height()) + ", width and height must be 1.." +
                        std::to_string(kMaxImageSide));
    }
    const uint64_t elem = static_cast<uint64_t>(ElementSize(info.encoding()));
    const uint64_t packed = uint64_t{info.width()} * ChannelCount(info.encoding()) * elem;
    if (info.step() < packed || info.step() % elem != 0) {
      return Reject(f, DecodeReason::kBadImage,
                    field + ".step is " + std::to_string(info.step()) + ", must be >= " +
                        std::to_string(packed) + " (width * channels * element size) and a " +
                        "multiple of " + std::to_string(elem));
    }
    const bool is_depth = info.encoding() == pb::DEPTH16U || info.encoding() == pb::DEPTH32F;
    if (is_depth && !(info.depth_scale() > 0.0)) {
      return Reject(f, DecodeReason::kBadImage,
                    field + ".depth_scale is " + Num(info.depth_scale()) + ", must be > 0");
    }
    const size_t index = info.blob_index();
    if (index >= wire_.blobs.size()) {
      return Reject(f, DecodeReason::kMissingBlob,
                    field + ".blob_index is " + std::to_string(index) + " but the message has " +
                        std::to_string(wire_.blobs.size()) + " blob frame(s)");
    }
    if (used_[index]) {
      return Reject(f, DecodeReason::kBadImage,
                    field + ".blob_index " + std::to_string(index) + " is used twice");
    }
    const Blob& blob = wire_.blobs[index];
    if (!blob) {
      return Reject(f, DecodeReason::kMissingBlob,
                    field + ": blob frame " + std::to_string(index) + " is null");
    }
    const uint64_t expected = uint64_t{info.height()} * info.step();
    if (blob->size() != expected) {
      return Reject(f, DecodeReason::kBlobSize,
                    field + ": blob " + std::to_string(index) + " is " +
                        std::to_string(blob->size()) + " bytes, expected height * step = " +
                        std::to_string(expected));
    }
    used_[index] = true;
    out->encoding = info.encoding();
    out->width = info.width();
    out->height = info.height();
    out->step = info.step();
    out->depth_scale = info.depth_scale();
    out->invalid_value = info.invalid_value();
    out->data = blob;
    return true;
  }

  /// Every blob frame must be referenced.
  bool CheckAllUsed(Failure* f) const {
    for (size_t i = 0; i < used_.size(); ++i) {
      if (!used_[i]) {
        return Reject(f, DecodeReason::kExtraBlob,
                      "blob frame " + std::to_string(i) + " of " + std::to_string(used_.size()) +
                          " is not referenced by any image");
      }
    }
    return true;
  }

 private:
  const WireMessage& wire_;
  std::vector<bool> used_;
};

constexpr std::initializer_list<Encoding> kRgbEncodings = {pb::RGB8};
constexpr std::initializer_list<Encoding> kDepthEncodings = {pb::DEPTH16U, pb::DEPTH32F};

/// Fills `info` from `image` and appends its blob; throws on a null blob (programmer error).
void AddImage(const Image& image, const char* what, pb::ImageInfo* info, WireMessage* wire) {
  if (!image.data) {
    throw std::invalid_argument(std::string("msgs::Encode: ") + what +
                                " image has no data (Image::data is null); allocate it with "
                                "Image::Allocate or attach a buffer");
  }
  info->set_encoding(image.encoding);
  info->set_width(image.width);
  info->set_height(image.height);
  const uint32_t packed =
      image.width * static_cast<uint32_t>(ChannelCount(image.encoding) * ElementSize(image.encoding));
  info->set_step(image.step == 0 ? packed : image.step);
  info->set_depth_scale(image.depth_scale);
  info->set_invalid_value(image.invalid_value);
  info->set_blob_index(static_cast<uint32_t>(wire->blobs.size()));
  wire->blobs.push_back(image.data);
}

template <class Pb>
WireMessage EncodeMeta(Pb meta, pb::MsgType type) {
  meta.mutable_header()->set_type(type);
  meta.mutable_header()->set_schema_version(kSchemaVersion);
  WireMessage wire;
  {
    // Deterministic: protobuf maps (NodeStatus counters, TrainerStatus losses) otherwise come
    // out in a per-process random order, and equal messages should be equal bytes (latching,
    // dedup, reproducible tests).
    gpb::io::StringOutputStream bytes(&wire.header);
    gpb::io::CodedOutputStream coded(&bytes);
    coded.SetSerializationDeterministic(true);
    meta.SerializeToCodedStream(&coded);
  }
  return wire;
}

// ---- Decoding: header and per-type checks ------------------------------------------------------

bool ParseHeaderOnly(const std::string& frame, pb::Header* out, Failure* f) {
  pb::HeaderOnly only;
  bool parsed;
  {
    // Invalid UTF-8 in a string field makes protobuf log an error per message: a flood of
    // garbage must not flood the log too (the rejection is counted instead).
    gpb::LogSilencer silence;
    parsed = only.ParseFromString(frame);
  }
  if (!parsed) {
    return Reject(f, DecodeReason::kUnparsable,
                  "header frame (" + std::to_string(frame.size()) +
                      " bytes) is not a protobuf message with a Header as field 1");
  }
  if (!only.has_header()) {
    return Reject(f, DecodeReason::kUnparsable,
                  "header: field 1 of the header frame (" + std::to_string(frame.size()) +
                      " bytes) is missing");
  }
  const pb::MsgType type = only.header().type();
  if (type == pb::MSG_UNKNOWN || !pb::MsgType_IsValid(type)) {
    return Reject(f, DecodeReason::kUnknownType,
                  "header.type is " + std::to_string(static_cast<int>(type)) +
                      ", not a known message type (sender built with a newer schema?)");
  }
  out->Swap(only.mutable_header());
  return true;
}

template <class Pb>
bool ParseMeta(const WireMessage& wire, pb::MsgType expected, Pb* meta, Failure* f) {
  const size_t size = WireSize(wire);
  const size_t limit = MaxMessageBytes();
  if (size > limit) {
    return Reject(f, DecodeReason::kOversized,
                  "message is " + std::to_string(size) + " bytes, above the limit of " +
                      std::to_string(limit) + " (msgs::SetMaxMessageBytes)");
  }
  pb::Header header;
  if (!ParseHeaderOnly(wire.header, &header, f)) return false;
  if (header.schema_version() < kMinSchemaVersion || header.schema_version() > kSchemaVersion) {
    return Reject(f, DecodeReason::kBadVersion,
                  "header.schema_version is " + std::to_string(header.schema_version()) +
                      ", this build reads " + std::to_string(kMinSchemaVersion) + ".." +
                      std::to_string(kSchemaVersion) + " (rebuild sender or receiver)");
  }
  if (header.type() != expected) {
    return Reject(f, DecodeReason::kTypeMismatch,
                  std::string("header.type is ") + TypeName(header.type()) + ", expected " +
                      TypeName(expected));
  }
  bool parsed;
  {
    gpb::LogSilencer silence;
    parsed = meta->ParseFromString(wire.header);
  }
  if (!parsed) {
    return Reject(f, DecodeReason::kUnparsable,
                  std::string("header frame is not a valid ") + TypeName(expected));
  }
  return CheckFinite(*meta, f);
}

bool NoBlobs(const WireMessage& wire, Failure* f) {
  if (!wire.blobs.empty()) {
    return Reject(f, DecodeReason::kExtraBlob,
                  std::to_string(wire.blobs.size()) + " blob frame(s) where none are expected");
  }
  return true;
}

bool DecodeInto(const WireMessage& wire, pb::PoseStamped* m, Failure* f) {
  return ParseMeta(wire, pb::POSE, m, f) && NoBlobs(wire, f) &&
         RequirePose(m, "pose", f);
}

bool DecodeInto(const WireMessage& wire, pb::CameraInfo* m, Failure* f) {
  return ParseMeta(wire, pb::CAMERA_INFO, m, f) && NoBlobs(wire, f) && CheckCameraInfo(*m, "", f);
}

bool DecodeInto(const WireMessage& wire, pb::PoseRequest* m, Failure* f) {
  return ParseMeta(wire, pb::POSE_REQUEST, m, f) && NoBlobs(wire, f) &&
         RequirePose(m, "pose", f) &&
         CheckNonNegative(m->deadline_ns(), "deadline_ns", f);
}

bool DecodeInto(const WireMessage& wire, pb::ModelVersion* m, Failure* f) {
  if (!ParseMeta(wire, pb::MODEL_VERSION, m, f) || !NoBlobs(wire, f)) return false;
  if (m->width() > kMaxImageSide || m->height() > kMaxImageSide) {
    return Reject(f, DecodeReason::kBadValue,
                  "width/height " + std::to_string(m->width()) + " x " +
                      std::to_string(m->height()) + " above " + std::to_string(kMaxImageSide));
  }
  return true;
}

bool DecodeInto(const WireMessage& wire, pb::TrainerStatus* m, Failure* f) {
  if (!ParseMeta(wire, pb::TRAINER_STATUS, m, f) || !NoBlobs(wire, f)) return false;
  if (m->steps_per_s() < 0) {
    return Reject(f, DecodeReason::kBadValue,
                  "steps_per_s is " + Num(m->steps_per_s()) + ", must be >= 0");
  }
  return true;
}

bool DecodeInto(const WireMessage& wire, pb::NodeStatus* m, Failure* f) {
  if (!ParseMeta(wire, pb::NODE_STATUS, m, f) || !NoBlobs(wire, f)) return false;
  if (m->uptime_s() < 0) {
    return Reject(f, DecodeReason::kBadValue,
                  "uptime_s is " + Num(m->uptime_s()) + ", must be >= 0");
  }
  return true;
}

bool DecodeInto(const WireMessage& wire, pb::RenderRequest* m, Failure* f) {
  if (!ParseMeta(wire, pb::RENDER_REQUEST, m, f) || !NoBlobs(wire, f)) return false;
  if (m->poses_size() > kMaxBatch) {
    return Reject(f, DecodeReason::kBadValue,
                  "poses has " + std::to_string(m->poses_size()) + " entries, at most " +
                      std::to_string(kMaxBatch));
  }
  for (int i = 0; i < m->poses_size(); ++i) {
    if (!CheckPose(m->mutable_poses(i), "poses[" + std::to_string(i) + "]", f)) return false;
  }
  return CheckNonNegative(m->deadline_ns(), "deadline_ns", f);
}

bool DecodeInto(const WireMessage& wire, RenderReplyMsg* m, Failure* f) {
  pb::RenderReply& meta = m->meta;
  if (!ParseMeta(wire, pb::RENDER_REPLY, &meta, f)) return false;
  if (meta.views_size() > kMaxBatch) {
    return Reject(f, DecodeReason::kBadValue,
                  "views has " + std::to_string(meta.views_size()) + " entries, at most " +
                      std::to_string(kMaxBatch));
  }
  // Images are all-or-nothing: a reply without blobs must not announce any image.
  bool announces_images = false;
  for (const auto& v : meta.views()) {
    announces_images = announces_images || v.rgb().encoding() != pb::ENCODING_UNKNOWN ||
                       v.depth().encoding() != pb::ENCODING_UNKNOWN;
  }
  const bool with_images = !wire.blobs.empty() || announces_images;
  BlobRefs refs(wire);
  m->images.clear();
  if (with_images) m->images.resize(2 * static_cast<size_t>(meta.views_size()));
  for (int i = 0; i < meta.views_size(); ++i) {
    const std::string field = "views[" + std::to_string(i) + "]";
    pb::ViewMeta* v = meta.mutable_views(i);
    if (!RequirePose(v, field + ".pose", f) ||
        !CheckUnit(v->coverage(), field + ".coverage", f) || !CheckGeometry(*v, field + ".", f)) {
      return false;
    }
    if (with_images &&
        (!refs.Take(v->rgb(), field + ".rgb", kRgbEncodings, &m->images[2 * i], f) ||
         !refs.Take(v->depth(), field + ".depth", kDepthEncodings, &m->images[2 * i + 1], f))) {
      return false;
    }
  }
  return refs.CheckAllUsed(f);
}

bool DecodeInto(const WireMessage& wire, pb::RenderReply* m, Failure* f) {
  RenderReplyMsg full;
  if (!DecodeInto(wire, &full, f)) return false;
  m->Swap(&full.meta);
  return true;
}

bool DecodeInto(const WireMessage& wire, RgbdFrame* m, Failure* f) {
  pb::RgbdFrame& meta = m->meta;
  if (!ParseMeta(wire, pb::RGBD_FRAME, &meta, f)) return false;
  switch (meta.camera_case()) {
    case pb::RgbdFrame::kCameraInfo:
      if (!CheckCameraInfo(meta.camera_info(), "camera_info", f)) return false;
      break;
    case pb::RgbdFrame::kCameraInfoId:
      if (meta.camera_info_id().empty()) {
        return Reject(f, DecodeReason::kBadValue, "camera_info_id is empty");
      }
      break;
    default:
      return Reject(f, DecodeReason::kBadValue, "camera_info / camera_info_id: neither is set");
  }
  if (meta.has_pose() && !CheckPose(meta.mutable_pose(), "pose", f)) return false;
  BlobRefs refs(wire);
  return refs.Take(meta.rgb(), "rgb", kRgbEncodings, &m->rgb, f) &&
         refs.Take(meta.depth(), "depth", kDepthEncodings, &m->depth, f) && refs.CheckAllUsed(f);
}

bool DecodeInto(const WireMessage& wire, View* m, Failure* f) {
  pb::View& meta = m->meta;
  if (!ParseMeta(wire, pb::VIEW, &meta, f) ||
      !RequirePose(&meta, "pose", f) ||
      !CheckUnit(meta.coverage(), "coverage", f) || !CheckGeometry(meta, "", f)) {
    return false;
  }
  BlobRefs refs(wire);
  return refs.Take(meta.rgb(), "rgb", kRgbEncodings, &m->rgb, f) &&
         refs.Take(meta.depth(), "depth", kDepthEncodings, &m->depth, f) && refs.CheckAllUsed(f);
}

/// Decodes into a fresh T (so *out stays untouched on failure); never throws.
template <class T>
bool DecodeNoCount(const WireMessage& wire, T* out, Failure* f) {
  try {
    T tmp;
    if (!DecodeInto(wire, &tmp, f)) return false;
    if (out != nullptr) *out = std::move(tmp);
    return true;
  } catch (const std::exception& e) {
    return Reject(f, DecodeReason::kInternal, std::string("decoder exception: ") + e.what());
  } catch (...) {
    return Reject(f, DecodeReason::kInternal, "unknown decoder exception");
  }
}

/// Full validation of a message of the type its header announces (for DebugString).
bool ValidateAny(const WireMessage& wire, pb::MsgType type, Failure* f) {
  switch (type) {
    case pb::POSE: return DecodeNoCount<pb::PoseStamped>(wire, nullptr, f);
    case pb::CAMERA_INFO: return DecodeNoCount<pb::CameraInfo>(wire, nullptr, f);
    case pb::RGBD_FRAME: return DecodeNoCount<RgbdFrame>(wire, nullptr, f);
    case pb::POSE_REQUEST: return DecodeNoCount<pb::PoseRequest>(wire, nullptr, f);
    case pb::VIEW: return DecodeNoCount<View>(wire, nullptr, f);
    case pb::MODEL_VERSION: return DecodeNoCount<pb::ModelVersion>(wire, nullptr, f);
    case pb::TRAINER_STATUS: return DecodeNoCount<pb::TrainerStatus>(wire, nullptr, f);
    case pb::NODE_STATUS: return DecodeNoCount<pb::NodeStatus>(wire, nullptr, f);
    case pb::RENDER_REQUEST: return DecodeNoCount<pb::RenderRequest>(wire, nullptr, f);
    case pb::RENDER_REPLY: return DecodeNoCount<RenderReplyMsg>(wire, nullptr, f);
    default: return Reject(f, DecodeReason::kUnknownType, "unknown type");
  }
}

/// Collects every ImageInfo in `m` (any depth) by blob index, for labelling blobs.
void CollectImageInfos(const gpb::Message& m, std::vector<const pb::ImageInfo*>* by_blob) {
  if (m.GetDescriptor() == pb::ImageInfo::descriptor()) {
    const auto& info = static_cast<const pb::ImageInfo&>(m);
    if (info.encoding() != pb::ENCODING_UNKNOWN && info.blob_index() < by_blob->size()) {
      (*by_blob)[info.blob_index()] = &info;
    }
    return;
  }
  const gpb::Reflection* refl = m.GetReflection();
  std::vector<const gpb::FieldDescriptor*> fields;
  refl->ListFields(m, &fields);
  for (const auto* fd : fields) {
    if (fd->cpp_type() != gpb::FieldDescriptor::CPPTYPE_MESSAGE) continue;
    if (fd->is_repeated()) {
      for (int i = 0; i < refl->FieldSize(m, fd); ++i) {
        CollectImageInfos(refl->GetRepeatedMessage(m, fd, i), by_blob);
      }
    } else {
      CollectImageInfos(refl->GetMessage(m, fd), by_blob);
    }
  }
}

}  // namespace

// ---- Public API --------------------------------------------------------------------------------

void SetMaxMessageBytes(size_t bytes) { g_max_message_bytes.store(bytes); }
size_t MaxMessageBytes() { return g_max_message_bytes.load(); }

const char* TypeName(pb::MsgType type) {
  switch (type) {
    case pb::POSE: return "PoseStamped";
    case pb::CAMERA_INFO: return "CameraInfo";
    case pb::RGBD_FRAME: return "RgbdFrame";
    case pb::POSE_REQUEST: return "PoseRequest";
    case pb::VIEW: return "View";
    case pb::MODEL_VERSION: return "ModelVersion";
    case pb::TRAINER_STATUS: return "TrainerStatus";
    case pb::NODE_STATUS: return "NodeStatus";
    case pb::RENDER_REQUEST: return "RenderRequest";
    case pb::RENDER_REPLY: return "RenderReply";
    default: return "Unknown";
  }
}

WireMessage Encode(const pb::PoseStamped& msg) { return EncodeMeta(msg, pb::POSE); }
WireMessage Encode(const pb::CameraInfo& msg) { return EncodeMeta(msg, pb::CAMERA_INFO); }
WireMessage Encode(const pb::PoseRequest& msg) { return EncodeMeta(msg, pb::POSE_REQUEST); }
WireMessage Encode(const pb::ModelVersion& msg) { return EncodeMeta(msg, pb::MODEL_VERSION); }
WireMessage Encode(const pb::TrainerStatus& msg) { return EncodeMeta(msg, pb::TRAINER_STATUS); }
WireMessage Encode(const pb::NodeStatus& msg) { return EncodeMeta(msg, pb::NODE_STATUS); }
WireMessage Encode(const pb::RenderRequest& msg) { return EncodeMeta(msg, pb::RENDER_REQUEST); }

WireMessage Encode(const pb::RenderReply& msg) {
  pb::RenderReply meta = msg;
  for (auto& v : *meta.mutable_views()) {
    v.clear_rgb();
    v.clear_depth();
  }
  return EncodeMeta(std::move(meta), pb::RENDER_REPLY);
}

WireMessage Encode(const RenderReplyMsg& msg) {
  const size_t views = static_cast<size_t>(msg.meta.views_size());
  if (!msg.images.empty() && msg.images.size() != 2 * views) {
    throw std::invalid_argument("msgs::Encode(RenderReplyMsg): " +
                                std::to_string(msg.images.size()) + " images for " +
                                std::to_string(views) +
                                " views; give 2 per view (rgb, depth) or none");
  }
  if (msg.images.empty()) return Encode(msg.meta);
  pb::RenderReply meta = msg.meta;
  WireMessage blobs;
  for (size_t i = 0; i < views; ++i) {
    AddImage(msg.images[2 * i], "rgb", meta.mutable_views(i)->mutable_rgb(), &blobs);
    AddImage(msg.images[2 * i + 1], "depth", meta.mutable_views(i)->mutable_depth(), &blobs);
  }
  WireMessage wire = EncodeMeta(std::move(meta), pb::RENDER_REPLY);
  wire.blobs = std::move(blobs.blobs);
  return wire;
}

WireMessage Encode(const RgbdFrame& msg) {
  pb::RgbdFrame meta = msg.meta;
  WireMessage blobs;
  AddImage(msg.rgb, "rgb", meta.mutable_rgb(), &blobs);
  AddImage(msg.depth, "depth", meta.mutable_depth(), &blobs);
  WireMessage wire = EncodeMeta(std::move(meta), pb::RGBD_FRAME);
  wire.blobs = std::move(blobs.blobs);
  return wire;
}

WireMessage Encode(const View& msg) {
  pb::View meta = msg.meta;
  WireMessage blobs;
  AddImage(msg.rgb, "rgb", meta.mutable_rgb(), &blobs);
  AddImage(msg.depth, "depth", meta.mutable_depth(), &blobs);
  WireMessage wire = EncodeMeta(std::move(meta), pb::VIEW);
  wire.blobs = std::move(blobs.blobs);
  return wire;
}

template <class T>
bool Decode(const WireMessage& wire, T* out, std::string* error, DecodeReason* reason) {
  Failure f;
  const bool ok = DecodeNoCount(wire, out, &f);
  DecodeStats::Global().Count(ok ? DecodeReason::kOk : f.reason);
  if (reason != nullptr) *reason = ok ? DecodeReason::kOk : f.reason;
  if (!ok && error != nullptr) *error = f.text;
  return ok;
}

#define P2I_MSGS_DECODE(T)                                                                   \
  template bool Decode<T>(const WireMessage&, T*, std::string*, DecodeReason*);              \
  bool Decode(const WireMessage& wire, T* out, std::string* error) {                         \
    return Decode<T>(wire, out, error, nullptr);                                             \
  }
P2I_MSGS_DECODE(pb::PoseStamped)
P2I_MSGS_DECODE(pb::CameraInfo)
P2I_MSGS_DECODE(pb::PoseRequest)
P2I_MSGS_DECODE(pb::ModelVersion)
P2I_MSGS_DECODE(pb::TrainerStatus)
P2I_MSGS_DECODE(pb::NodeStatus)
P2I_MSGS_DECODE(pb::RenderRequest)
P2I_MSGS_DECODE(pb::RenderReply)
P2I_MSGS_DECODE(RgbdFrame)
P2I_MSGS_DECODE(View)
P2I_MSGS_DECODE(RenderReplyMsg)
#undef P2I_MSGS_DECODE

bool PeekHeader(const std::string& header_frame, pb::Header* out, std::string* error) {
  Failure f;
  pb::Header header;
  bool ok = false;
  try {
    ok = ParseHeaderOnly(header_frame, &header, &f);
  } catch (const std::exception& e) {
    Reject(&f, DecodeReason::kInternal, e.what());
  }
  if (!ok) {
    if (error != nullptr) *error = f.text;
    return false;
  }
  if (out != nullptr) out->Swap(&header);
  return true;
}

bool ValidatePose(pb::Pose* pose, const std::string& field, std::string* error) {
  Failure f;
  if (CheckPose(pose, field, &f)) return true;
  if (error != nullptr) *error = f.text;
  return false;
}

std::string DebugString(const WireMessage& wire) {
  std::ostringstream out;
  try {
    pb::Header header;
    Failure f;
    if (!ParseHeaderOnly(wire.header, &header, &f)) {
      out << "INVALID: " << f.text << "\n";
    } else {
      out << "type: " << TypeName(header.type()) << "\n";
      Failure why;
      if (!ValidateAny(wire, header.type(), &why)) out << "INVALID: " << why.text << "\n";
    }
    std::vector<const pb::ImageInfo*> infos(wire.blobs.size(), nullptr);
    std::unique_ptr<gpb::Message> meta = NewMessage(header.type());
    bool parsed = false;
    if (meta) {
      gpb::LogSilencer silence;
      parsed = meta->ParseFromString(wire.header);
    }
    if (parsed) {
      out << meta->DebugString();
      CollectImageInfos(*meta, &infos);
    } else if (meta) {
      out << "<header frame: " << wire.header.size() << " bytes, not a valid "
          << TypeName(header.type()) << ">\n";
    }
    for (size_t i = 0; i < wire.blobs.size(); ++i) {
      const size_t bytes = wire.blobs[i] ? wire.blobs[i]->size() : 0;
      out << "<blob " << i << ": ";
      if (infos[i] != nullptr) {
        out << infos[i]->width() << " x " << infos[i]->height() << " "
            << EncodingName(infos[i]->encoding()) << ", ";
      }
      out << bytes << " bytes" << (wire.blobs[i] ? "" : " (null)") << ">\n";
    }
  } catch (const std::exception& e) {
    out << "INVALID: internal: " << e.what() << "\n";
  }
  return out.str();
}

std::unique_ptr<google::protobuf::Message> NewMessage(pb::MsgType type) {
  switch (type) {
    case pb::POSE: return std::make_unique<pb::PoseStamped>();
    case pb::CAMERA_INFO: return std::make_unique<pb::CameraInfo>();
    case pb::RGBD_FRAME: return std::make_unique<pb::RgbdFrame>();
    case pb::POSE_REQUEST: return std::make_unique<pb::PoseRequest>();
    case pb::VIEW: return std::make_unique<pb::View>();
    case pb::MODEL_VERSION: return std::make_unique<pb::ModelVersion>();
    case pb::TRAINER_STATUS: return std::make_unique<pb::TrainerStatus>();
    case pb::NODE_STATUS: return std::make_unique<pb::NodeStatus>();
    case pb::RENDER_REQUEST: return std::make_unique<pb::RenderRequest>();
    case pb::RENDER_REPLY: return std::make_unique<pb::RenderReply>();
    default: return nullptr;
  }
}

}  // namespace p2i::msgs
