/// @file inline_blobs.cc
/// @brief ImageInfo.data <-> blob frames: a run-time extended copy of p2i.proto's descriptor,
/// appended protobuf fields on the way in, reflection on the way out.
#include "recording/inline_blobs.h"

#include <cstring>
#include <functional>
#include <map>
#include <mutex>

#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>

#include "msgs/p2i.pb.h"
#include "recording/proto_schema.h"

namespace p2i::recording {

namespace gp = google::protobuf;

namespace {

constexpr const char* kImageInfo = "p2i.msgs.pb.ImageInfo";
constexpr int kDataField = 8;

/// p2i.proto with ImageInfo.data, in its own pool (built once, immutable afterwards).
struct RecordingPool {
  gp::FileDescriptorProto file;
  gp::DescriptorPool pool;
  gp::DynamicMessageFactory factory{&pool};
  RecordingPool() {
    msgs::pb::Header::descriptor()->file()->CopyTo(&file);
    for (auto& m : *file.mutable_message_type()) {
      if (m.name() != "ImageInfo") continue;
      auto* f = m.add_field();
      f->set_name("data");
      f->set_number(kDataField);
      f->set_label(gp::FieldDescriptorProto::LABEL_OPTIONAL);
      f->set_type(gp::FieldDescriptorProto::TYPE_BYTES);
      f->set_json_name("data");
    }
    pool.BuildFile(file);
  }
  static const RecordingPool& Get() {
    static const RecordingPool p;
    return p;
  }
};

void AppendVarint(uint64_t v, std::string* out) {
  while (v >= 0x80) {
    out->push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out->push_back(static_cast<char>(v));
}

size_t VarintSize(uint64_t v) {
  size_t n = 1;
  while (v >= 0x80) v >>= 7, ++n;
  return n;
}

/// header frame + for each singular top-level ImageInfo field F holding blob b:
///   [tag F, LEN][len][tag 8, LEN][blob size][blob bytes]
/// which parses as the header with F.data = blob (a repeated field would append instead of
/// merging: types with images inside repeated fields use Reflected below).
class AppendedMessage : public InlinedMessage {
 public:
  struct Part {
    std::string prefix;  // tags and lengths
    msgs::Blob blob;
  };
  AppendedMessage(const std::string& header, std::vector<Part> parts)
      : header_(header), parts_(std::move(parts)) {
    size_ = header_.size();
    for (const auto& p : parts_) size_ += p.prefix.size() + p.blob->size();
  }
  size_t Size() const override { return size_; }
  void WriteTo(uint8_t* dst) const override {
    std::memcpy(dst, header_.data(), header_.size());
    dst += header_.size();
    for (const auto& p : parts_) {
      std::memcpy(dst, p.prefix.data(), p.prefix.size());
      dst += p.prefix.size();
      std::memcpy(dst, p.blob->data(), p.blob->size());
      dst += p.blob->size();
    }
  }

 private:
  const std::string& header_;
  std::vector<Part> parts_;
  size_t size_ = 0;
};

class SerializedMessage : public InlinedMessage {
 public:
  explicit SerializedMessage(std::string bytes) : bytes_(std::move(bytes)) {}
  size_t Size() const override { return bytes_.size(); }
  void WriteTo(uint8_t* dst) const override { std::memcpy(dst, bytes_.data(), bytes_.size()); }

 private:
  std::string bytes_;
};

/// Calls `fn` for every ImageInfo sub-message present in `msg` (recursively).
void ForEachImageInfo(gp::Message* msg, const std::function<void(gp::Message*)>& fn) {
  const gp::Descriptor* d = msg->GetDescriptor();
  const gp::Reflection* r = msg->GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const gp::FieldDescriptor* f = d->field(i);
    if (f->cpp_type() != gp::FieldDescriptor::CPPTYPE_MESSAGE || f->is_map()) continue;
    const bool image = f->message_type()->full_name() == kImageInfo;
    if (f->is_repeated()) {
      for (int k = 0; k < r->FieldSize(*msg, f); ++k) {
        gp::Message* sub = r->MutableRepeatedMessage(msg, f, k);
        image ? fn(sub) : ForEachImageInfo(sub, fn);
      }
    } else if (r->HasField(*msg, f)) {
      gp::Message* sub = r->MutableMessage(msg, f);
      image ? fn(sub) : ForEachImageInfo(sub, fn);
    }
  }
}

std::unique_ptr<gp::Message> NewRecorded(const std::string& type_name) {
  const RecordingPool& rp = RecordingPool::Get();
  const gp::Descriptor* d = rp.pool.FindMessageTypeByName(type_name);
  if (!d) return nullptr;
  return std::unique_ptr<gp::Message>(
      const_cast<gp::DynamicMessageFactory&>(rp.factory).GetPrototype(d)->New());
}

}  // namespace

std::string RecordingSchema(const gp::Descriptor* type) {
  if (type->file() != msgs::pb::Header::descriptor()->file()) return FileDescriptorSetFor(type);
  gp::FileDescriptorSet set;
  *set.add_file() = RecordingPool::Get().file;
  return set.SerializeAsString();
}

std::unique_ptr<InlinedMessage> InlinedMessage::Make(const gp::Descriptor* type,
                                                     const msgs::WireMessage& m,
                                                     std::string* error) {
  const gp::Message* proto = gp::MessageFactory::generated_factory()->GetPrototype(type);
  std::unique_ptr<gp::Message> msg(proto ? proto->New() : nullptr);
  if (!msg || !msg->ParseFromString(m.header)) {
    *error = "header frame does not parse as " + type->full_name();
    return nullptr;
  }
  const gp::Reflection* r = msg->GetReflection();
  std::vector<AppendedMessage::Part> parts;
  bool nested = false, ok = true;
  for (int i = 0; i < type->field_count() && ok; ++i) {
    const gp::FieldDescriptor* f = type->field(i);
    if (f->cpp_type() != gp::FieldDescriptor::CPPTYPE_MESSAGE || f->is_map()) continue;
    if (f->message_type()->full_name() != kImageInfo) {
      // images below another message (RenderReply.views): take the general path
      if (f->is_repeated() ? r->FieldSize(*msg, f) > 0 : false) nested = true;
      continue;
    }
    if (f->is_repeated() || !r->HasField(*msg, f)) continue;
    const auto& info = static_cast<const msgs::pb::ImageInfo&>(r->GetMessage(*msg, f));
    if (info.encoding() == msgs::pb::ENCODING_UNKNOWN) continue;
    if (info.blob_index() >= m.blobs.size() || !m.blobs[info.blob_index()]) {
      *error = type->name() + "." + f->name() + " names blob " +
               std::to_string(info.blob_index()) + " of " + std::to_string(m.blobs.size());
      ok = false;
      break;
    }
    const msgs::Blob& blob = m.blobs[info.blob_index()];
    AppendedMessage::Part p;
    p.blob = blob;
    const uint64_t inner = 1 + VarintSize(blob->size()) + blob->size();
    AppendVarint((static_cast<uint64_t>(f->number()) << 3) | 2, &p.prefix);
    AppendVarint(inner, &p.prefix);
    AppendVarint((kDataField << 3) | 2, &p.prefix);
    AppendVarint(blob->size(), &p.prefix);
    parts.push_back(std::move(p));
  }
  if (!ok) return nullptr;
  if (!nested) return std::make_unique<AppendedMessage>(m.header, std::move(parts));
  // General path: parse into the recording pool's type, set every ImageInfo.data, serialize.
  std::unique_ptr<gp::Message> rec = NewRecorded(type->full_name());
  if (!rec || !rec->ParseFromString(m.header)) {
    *error = "header frame does not parse as recorded " + type->full_name();
    return nullptr;
  }
  ForEachImageInfo(rec.get(), [&](gp::Message* info) {
    const gp::Descriptor* d = info->GetDescriptor();
    const gp::Reflection* ir = info->GetReflection();
    if (ir->GetEnumValue(*info, d->FindFieldByName("encoding")) == 0) return;
    const uint32_t index = ir->GetUInt32(*info, d->FindFieldByName("blob_index"));
    if (index >= m.blobs.size() || !m.blobs[index]) {
      *error = "an ImageInfo names blob " + std::to_string(index) + " of " +
               std::to_string(m.blobs.size());
      ok = false;
      return;
    }
    const auto& b = *m.blobs[index];
    ir->SetString(info, d->FindFieldByName("data"),
                  std::string(reinterpret_cast<const char*>(b.data()), b.size()));
  });
  if (!ok) return nullptr;
  return std::make_unique<SerializedMessage>(rec->SerializeAsString());
}

bool ExtractBlobs(const std::string& type_name, const uint8_t* data, size_t size,
                  msgs::WireMessage* out, std::string* error) {
  std::unique_ptr<gp::Message> msg = NewRecorded(type_name);
  if (!msg) {
    *error = "unknown recorded type " + type_name;
    return false;
  }
  if (!msg->ParseFromArray(data, static_cast<int>(size))) {
    *error = "recorded message does not parse as " + type_name;
    return false;
  }
  std::map<uint32_t, msgs::Blob> blobs;
  bool ok = true;
  ForEachImageInfo(msg.get(), [&](gp::Message* info) {
    const gp::Descriptor* d = info->GetDescriptor();
    const gp::Reflection* r = info->GetReflection();
    const gp::FieldDescriptor* data_field = d->FindFieldByName("data");
    if (r->GetEnumValue(*info, d->FindFieldByName("encoding")) == 0) return;
    const uint32_t index = r->GetUInt32(*info, d->FindFieldByName("blob_index"));
    std::string scratch;
    const std::string& bytes = r->GetStringReference(*info, data_field, &scratch);
    if (blobs.count(index)) {
      *error = "two images share blob " + std::to_string(index);
      ok = false;
      return;
    }
    blobs[index] = std::make_shared<const msgs::Bytes>(bytes.begin(), bytes.end());
    r->ClearField(info, data_field);
  });
  if (!ok) return false;
  out->blobs.clear();
  for (const auto& [index, blob] : blobs) {
    if (index != out->blobs.size()) {
      *error = "blob indexes are not 0..n-1 (found " + std::to_string(index) + ")";
      return false;
    }
    out->blobs.push_back(blob);
  }
  out->header = msg->SerializeAsString();
  return true;
}

}  // namespace p2i::recording
