/// @file fuzz_test.cc
/// @brief Thousands of random and mutated messages thrown at every decoder (deterministic seed).
#include <catch2/catch.hpp>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/message.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "msgs/codec.h"
#include "tests/msgs/samples.h"

namespace p2i::msgs {
namespace {

namespace gpb = google::protobuf;

/// One decoder under test: decodes, and on success re-encodes the output and decodes it again
/// (whatever a decoder accepts must be a valid message).
struct Decoder {
  pb::MsgType type;
  const char* name;
  std::function<bool(const WireMessage&, std::string*, DecodeReason*, bool* reencode_ok)> run;
};

template <class T>
Decoder MakeDecoder(const char* name) {
  return {TypeOf<T>(), name,
          [](const WireMessage& wire, std::string* error, DecodeReason* reason, bool* again) {
            T out;
            if (!Decode(wire, &out, error, reason)) return false;
            T twice;
            std::string why;
            *again = Decode(Encode(out), &twice, &why);
            return true;
          }};
}

std::vector<Decoder> AllDecoders() {
  return {MakeDecoder<pb::PoseStamped>("PoseStamped"),
          MakeDecoder<pb::CameraInfo>("CameraInfo"),
          MakeDecoder<pb::PoseRequest>("PoseRequest"),
          MakeDecoder<pb::ModelVersion>("ModelVersion"),
          MakeDecoder<pb::TrainerStatus>("TrainerStatus"),
          MakeDecoder<pb::NodeStatus>("NodeStatus"),
          MakeDecoder<pb::RenderRequest>("RenderRequest"),
          MakeDecoder<pb::RenderReply>("pb::RenderReply"),
          MakeDecoder<RgbdFrame>("RgbdFrame"),
          MakeDecoder<View>("View"),
          MakeDecoder<RenderReplyMsg>("RenderReplyMsg")};
}

/// A valid message of a random type.
WireMessage RandomValid(testing::Samples& s) {
  const uint32_t w = s.Int(1, 24);
  const uint32_t h = s.Int(1, 16);
  switch (s.Int(0, 10)) {
    case 0: return Encode(s.MakePoseStamped());
    case 1: return Encode(s.MakeCameraInfo());
    case 2: return Encode(s.MakePoseRequest());
    case 3: return Encode(s.MakeModelVersion());
    case 4: return Encode(s.MakeTrainerStatus());
    case 5: return Encode(s.MakeNodeStatus());
    case 6: return Encode(s.MakeRenderRequest(static_cast<int>(s.Int(1, 4))));
    case 7: return Encode(s.MakeRenderReply(static_cast<int>(s.Int(1, 3)), w, h));
    case 8: return Encode(s.MakeRgbdFrame(w, h));
    case 9: return Encode(s.MakeView(w, h));
    default: {
      RenderReplyMsg r = s.MakeRenderReply(static_cast<int>(s.Int(0, 3)));
      r.images.clear();
      return Encode(r);
    }
  }
}

/// Kinds of damage. "Invalid" kinds must always be rejected by the decoder of the original type.
enum class Mutation {
  kNone,             // valid: must decode with its own decoder
  kRandomBytes,      // header frame of random bytes, random blobs
  kTruncated,        // header frame cut short
  kFlipHeaderBytes,  // random bytes of the header frame changed (may stay valid)
  kDropBlob,         // invalid
  kExtraBlob,        // invalid
  kNullBlob,         // invalid
  kBlobSize,         // invalid: one blob grown or shrunk
  kNonFinite,        // invalid: NaN or +-inf in a random float/double field
  kBadQuaternion,    // invalid: an orientation scaled out of tolerance
  kNearQuaternion,   // valid: an orientation scaled within tolerance
  kWrongType,        // invalid for the original type
  kWrongVersion,     // invalid
  kImageGeometry,    // random width/height/step/encoding/blob_index in an ImageInfo (may stay valid)
  kCount
};

bool AlwaysInvalid(Mutation m) {
  switch (m) {
    case Mutation::kDropBlob:
    case Mutation::kExtraBlob:
    case Mutation::kNullBlob:
    case Mutation::kBlobSize:
    case Mutation::kNonFinite:
    case Mutation::kBadQuaternion:
    case Mutation::kWrongType:
    case Mutation::kWrongVersion: return true;
    default: return false;
  }
}

/// All sub-messages of `m` of type D (mutable), e.g. every Quaternion or ImageInfo.
template <class D>
void FindAll(gpb::Message* m, std::vector<D*>* found) {
  if (m->GetDescriptor() == D::descriptor()) {
    found->push_back(static_cast<D*>(m));
    return;
  }
  const gpb::Reflection* refl = m->GetReflection();
  std::vector<const gpb::FieldDescriptor*> fields;
  refl->ListFields(*m, &fields);
  for (const auto* fd : fields) {
    if (fd->cpp_type() != gpb::FieldDescriptor::CPPTYPE_MESSAGE || fd->is_map()) continue;
    if (fd->is_repeated()) {
      for (int i = 0; i < refl->FieldSize(*m, fd); ++i) {
        FindAll(refl->MutableRepeatedMessage(m, fd, i), found);
      }
    } else {
      FindAll(refl->MutableMessage(m, fd), found);
    }
  }
}

/// Every (message, double field) slot, set or not, in the fields that are present (maps aside:
/// they are covered by validation_test).
void FindDoubleSlots(gpb::Message* m,
                     std::vector<std::pair<gpb::Message*, const gpb::FieldDescriptor*>>* slots) {
  const gpb::Descriptor* d = m->GetDescriptor();
  const gpb::Reflection* refl = m->GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const gpb::FieldDescriptor* fd = d->field(i);
    if (fd->is_map()) continue;
    if (fd->cpp_type() == gpb::FieldDescriptor::CPPTYPE_DOUBLE && !fd->is_repeated()) {
      slots->push_back({m, fd});
    } else if (fd->cpp_type() == gpb::FieldDescriptor::CPPTYPE_MESSAGE) {
      if (fd->is_repeated()) {
        for (int k = 0; k < refl->FieldSize(*m, fd); ++k) {
          FindDoubleSlots(refl->MutableRepeatedMessage(m, fd, k), slots);
        }
      } else if (refl->HasField(*m, fd)) {
        FindDoubleSlots(refl->MutableMessage(m, fd), slots);
      }
    }
  }
}

Blob RandomBlob(testing::Samples& s, size_t max) {
  auto b = std::make_shared<Bytes>(s.Int(0, static_cast<uint32_t>(max)));
  for (auto& v : *b) v = static_cast<uint8_t>(s.rng()());
  return b;
}

/// The mutations of the frames themselves (kRandomBytes .. kBlobSize): header bytes and blobs.
/// Returns false if `mutation` does not apply to `wire` (e.g. it has no blob).
bool MutateFrames(Mutation mutation, testing::Samples& s, WireMessage* wire) {
  switch (mutation) {
    case Mutation::kRandomBytes: {
      std::string bytes(s.Int(0, 300), '\0');
      for (char& c : bytes) c = static_cast<char>(s.rng()());
      wire->header = bytes;
      wire->blobs.clear();
      for (uint32_t i = s.Int(0, 3); i > 0; --i) wire->blobs.push_back(RandomBlob(s, 2000));
      return true;
    }
    case Mutation::kTruncated:
      if (wire->header.empty()) return false;
      wire->header.resize(s.Int(0, static_cast<uint32_t>(wire->header.size() - 1)));
      return true;
    case Mutation::kFlipHeaderBytes:
      if (wire->header.empty()) return false;
      for (uint32_t i = s.Int(1, 4); i > 0; --i) {
        const size_t at = s.Int(0, static_cast<uint32_t>(wire->header.size() - 1));
        wire->header[at] = static_cast<char>(wire->header[at] ^ (1 + s.Int(0, 254)));
      }
      return true;
    case Mutation::kDropBlob:
      if (wire->blobs.empty()) return false;
      wire->blobs.erase(wire->blobs.begin() + s.Int(0, static_cast<uint32_t>(wire->blobs.size() - 1)));
      return true;
    case Mutation::kExtraBlob:
      wire->blobs.insert(wire->blobs.begin() + s.Int(0, static_cast<uint32_t>(wire->blobs.size())),
                         RandomBlob(s, 3000));
      return true;
    case Mutation::kNullBlob:
      if (wire->blobs.empty()) return false;
      wire->blobs[s.Int(0, static_cast<uint32_t>(wire->blobs.size() - 1))] = nullptr;
      return true;
    case Mutation::kBlobSize: {
      if (wire->blobs.empty()) return false;
      Blob& b = wire->blobs[s.Int(0, static_cast<uint32_t>(wire->blobs.size() - 1))];
      const int delta = static_cast<int>(s.Int(1, 64)) * (s.Int(0, 1) ? 1 : -1);
      const size_t n = delta < 0 && static_cast<size_t>(-delta) > b->size() ? 0 : b->size() + delta;
      if (n == b->size()) return false;
      b = std::make_shared<const Bytes>(n, 7);
      return true;
    }
    default:
      return false;
  }
}

/// kNonFinite: NaN or +-inf in a random double field of `meta`.
bool SetNonFinite(testing::Samples& s, gpb::Message* meta) {
  std::vector<std::pair<gpb::Message*, const gpb::FieldDescriptor*>> slots;
  FindDoubleSlots(meta, &slots);
  if (slots.empty()) return false;
  const auto& [m, fd] = slots[s.Int(0, static_cast<uint32_t>(slots.size() - 1))];
  const double bad[] = {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity(),
                        -std::numeric_limits<double>::infinity()};
  m->GetReflection()->SetDouble(m, fd, bad[s.Int(0, 2)]);
  return true;
}

/// kBadQuaternion / kNearQuaternion: one orientation of `meta` scaled out of / within tolerance.
bool ScaleQuaternion(Mutation mutation, testing::Samples& s, gpb::Message* meta) {
  std::vector<pb::Quaternion*> quats;
  FindAll(meta, &quats);
  if (quats.empty()) return false;
  // Scales chosen well clear of the 1e-3 threshold on either side.
  const double scale = mutation == Mutation::kNearQuaternion
                           ? 1.0 + s.Uniform(-5e-4, 5e-4)
                           : (s.Int(0, 1) ? s.Uniform(1.002, 3.0) : s.Uniform(0.0, 0.998));
  pb::Quaternion* q = quats[s.Int(0, static_cast<uint32_t>(quats.size() - 1))];
  q->set_x(q->x() * scale);
  q->set_y(q->y() * scale);
  q->set_z(q->z() * scale);
  q->set_w(q->w() * scale);
  return true;
}

/// kImageGeometry: a random width, height, step, encoding, blob_index or depth_scale in one
/// ImageInfo of `meta`.
bool BreakImageGeometry(testing::Samples& s, gpb::Message* meta) {
  std::vector<pb::ImageInfo*> infos;
  FindAll(meta, &infos);
  if (infos.empty()) return false;
  pb::ImageInfo* info = infos[s.Int(0, static_cast<uint32_t>(infos.size() - 1))];
  switch (s.Int(0, 5)) {
    case 0: info->set_width(s.Int(0, 1) ? 0 : s.Int(0, 40000)); break;
    case 1: info->set_height(s.Int(0, 1) ? 0 : s.Int(0, 40000)); break;
    case 2: info->set_step(s.Int(0, 200)); break;
    case 3: info->set_encoding(static_cast<pb::Encoding>(s.Int(0, 7))); break;
    case 4: info->set_blob_index(s.Int(0, 8)); break;
    default: info->set_depth_scale(s.Uniform(-1, 1)); break;
  }
  return true;
}

/// The mutations of the decoded header message `meta` (of type `type`): kNonFinite ..
/// kImageGeometry. Returns false if `mutation` does not apply (e.g. no quaternion in it).
bool MutateFields(Mutation mutation, pb::MsgType type, testing::Samples& s, gpb::Message* meta) {
  auto* header = static_cast<pb::Header*>(
      meta->GetReflection()->MutableMessage(meta, meta->GetDescriptor()->FindFieldByNumber(1)));
  switch (mutation) {
    case Mutation::kNonFinite:
      return SetNonFinite(s, meta);
    case Mutation::kBadQuaternion:
    case Mutation::kNearQuaternion:
      return ScaleQuaternion(mutation, s, meta);
    case Mutation::kWrongType: {
      int t;
      do {
        t = static_cast<int>(s.Int(0, 13));
      } while (t == type);
      header->set_type(static_cast<pb::MsgType>(t));
      return true;
    }
    case Mutation::kWrongVersion:
      header->set_schema_version(s.Int(0, 1) ? 0 : kSchemaVersion + s.Int(1, 1000));
      return true;
    case Mutation::kImageGeometry:
      return BreakImageGeometry(s, meta);
    default:
      return false;
  }
}

/// Applies `mutation` to `wire` (of type `type`). Returns false if it does not apply to this
/// message (e.g. no quaternion in it); the caller then picks another.
bool Mutate(Mutation mutation, pb::MsgType type, testing::Samples& s, WireMessage* wire) {
  auto meta = NewMessage(type);
  REQUIRE(meta->ParseFromString(wire->header));
  if (mutation == Mutation::kNone) return true;
  if (mutation <= Mutation::kBlobSize) return MutateFrames(mutation, s, wire);
  if (!MutateFields(mutation, type, s, meta.get())) return false;
  wire->header.clear();
  gpb::io::StringOutputStream bytes(&wire->header);
  gpb::io::CodedOutputStream coded(&bytes);
  coded.SetSerializationDeterministic(true);  // map order is random per process otherwise
  meta->SerializeToCodedStream(&coded);
  return true;
}

TEST_CASE("fuzz: 12000 random and mutated messages at every decoder", "[unit]") {
  testing::Samples s(20261122);
  const std::vector<Decoder> decoders = AllDecoders();
  constexpr int kMessages = 12000;
  std::array<int, static_cast<int>(Mutation::kCount)> per_mutation{};
  int valid_decoded = 0, invalid_rejected = 0;
  uint64_t rejections_seen = 0;
  const uint64_t rejected_before = DecodeStats::Global().Rejected();
  for (int i = 0; i < kMessages; ++i) {
    WireMessage wire = RandomValid(s);
    pb::Header original;
    std::string error;
    REQUIRE(PeekHeader(wire.header, &original, &error));
    Mutation mutation;
    do {
      mutation = static_cast<Mutation>(s.Int(0, static_cast<uint32_t>(Mutation::kCount) - 1));
    } while (!Mutate(mutation, original.type(), s, &wire));
    ++per_mutation[static_cast<int>(mutation)];

    for (const Decoder& d : decoders) {
      INFO("message " << i << " mutation " << static_cast<int>(mutation) << " original type "
                      << TypeName(original.type()) << " decoder " << d.name);
      std::string why;
      DecodeReason reason = DecodeReason::kOk;
      bool reencode_ok = false;
      const uint64_t rejected_before_call = DecodeStats::Global().Rejected();
      const bool ok = d.run(wire, &why, &reason, &reencode_ok);
      const bool own_type = d.type == original.type();
      if (ok) {
        CHECK(reason == DecodeReason::kOk);
        CHECK(reencode_ok);
        if (AlwaysInvalid(mutation) && own_type) FAIL("accepted an invalid message");
      } else {
        ++rejections_seen;
        CHECK(reason != DecodeReason::kOk);
        CHECK(why.rfind(std::string(DecodeReasonName(reason)) + ": ", 0) == 0);
        CHECK(DecodeStats::Global().Rejected() == rejected_before_call + 1);
        CHECK(DecodeStats::Global().Get(reason) > 0);
        if ((mutation == Mutation::kNone || mutation == Mutation::kNearQuaternion) && own_type) {
          FAIL("rejected a valid message: " << why);
        }
        if (AlwaysInvalid(mutation) && own_type) ++invalid_rejected;
      }
      if ((mutation == Mutation::kNone || mutation == Mutation::kNearQuaternion) && own_type &&
          ok) {
        ++valid_decoded;
      }
      if (mutation == Mutation::kNone && !own_type) CHECK(reason == DecodeReason::kTypeMismatch);
    }
  }
  // Every mutation kind was exercised, and the counters saw every rejection.
  for (int m = 0; m < static_cast<int>(Mutation::kCount); ++m) {
    INFO("mutation " << m);
    CHECK(per_mutation[m] > 200);
  }
  CHECK(valid_decoded > 1000);
  CHECK(invalid_rejected > 4000);
  CHECK(DecodeStats::Global().Rejected() - rejected_before == rejections_seen);
}

TEST_CASE("fuzz: PeekHeader and DebugString survive random input", "[unit]") {
  testing::Samples s(7);
  for (int i = 0; i < 3000; ++i) {
    WireMessage wire = RandomValid(s);
    pb::Header h;
    std::string error;
    REQUIRE(PeekHeader(wire.header, &h, &error));
    const pb::MsgType type = h.type();
    Mutation mutation;
    do {
      mutation = static_cast<Mutation>(s.Int(1, static_cast<uint32_t>(Mutation::kCount) - 1));
    } while (!Mutate(mutation, type, s, &wire));
    const uint64_t rejected = DecodeStats::Global().Rejected();
    const std::string text = DebugString(wire);
    CHECK_FALSE(text.empty());
    CHECK(DecodeStats::Global().Rejected() == rejected);  // DebugString does not count
    // (A changed type may well be a valid message of the new type.)
    if (AlwaysInvalid(mutation) && mutation != Mutation::kWrongType) {
      CHECK(text.find("INVALID: ") != std::string::npos);
    }
    const bool peeked = PeekHeader(wire.header, &h, &error);
    if (!peeked) CHECK_FALSE(error.empty());
  }
}

}  // namespace
}  // namespace p2i::msgs
