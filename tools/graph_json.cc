/// @file graph_json.cc
/// @brief YAML/JSON text -> protobuf message (see graph_json.h).
#include "tools/graph_json.h"

#include <chrono>
#include <stdexcept>

#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

namespace p2i::tools {
namespace {

namespace gpb = google::protobuf;

nlohmann::json ToJson(const YAML::Node& n) {
  if (n.IsMap()) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& kv : n) j[kv.first.as<std::string>()] = ToJson(kv.second);
    return j;
  }
  if (n.IsSequence()) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& e : n) j.push_back(ToJson(e));
    return j;
  }
  if (n.IsNull()) return nullptr;
  const std::string s = n.Scalar();
  if (n.Tag() == "!") return s;  // quoted: a string
  if (s == "true" || s == "false") return s == "true";
  try {
    size_t used = 0;
    const long long i = std::stoll(s, &used);
    if (used == s.size()) return i;
  } catch (const std::exception&) {
  }
  try {
    size_t used = 0;
    const double d = std::stod(s, &used);
    if (used == s.size()) return d;
  } catch (const std::exception&) {
  }
  return s;  // enum names and strings
}

gpb::Message* MutableHeader(gpb::Message* msg) {
  const gpb::FieldDescriptor* f = msg->GetDescriptor()->FindFieldByNumber(1);
  if (f == nullptr || f->type() != gpb::FieldDescriptor::TYPE_MESSAGE)
    throw std::logic_error("message has no header field");
  return msg->GetReflection()->MutableMessage(msg, f);
}

}  // namespace

msgs::pb::MsgType MsgTypeFromName(const std::string& type) {
  std::string known;
  for (int t = 1; msgs::pb::MsgType_IsValid(t); ++t) {
    const auto mt = static_cast<msgs::pb::MsgType>(t);
    if (type == msgs::TypeName(mt)) return mt;
    known += std::string(known.empty() ? "" : ", ") + msgs::TypeName(mt);
  }
  throw std::invalid_argument("unknown message type '" + type + "' (known: " + known + ")");
}

std::unique_ptr<gpb::Message> MessageFromText(msgs::pb::MsgType type, const std::string& text,
                                              const std::string& publisher) {
  std::unique_ptr<gpb::Message> msg = msgs::NewMessage(type);
  if (!msg) throw std::invalid_argument(std::string("cannot build a ") + msgs::TypeName(type));
  std::string json = "{}";
  if (!text.empty()) {
    try {
      json = ToJson(YAML::Load(text)).dump();
    } catch (const YAML::Exception& e) {
      throw std::invalid_argument("value '" + text + "' is not YAML/JSON: " + e.what());
    }
  }
  gpb::util::JsonParseOptions options;
  const auto status = gpb::util::JsonStringToMessage(json, msg.get(), options);
  if (!status.ok()) {
    throw std::invalid_argument(std::string("value does not fit a ") + msgs::TypeName(type) +
                                " (fields of msgs/p2i.proto): " + status.ToString());
  }
  gpb::Message* h = MutableHeader(msg.get());
  const gpb::Reflection* r = h->GetReflection();
  const gpb::Descriptor* d = h->GetDescriptor();
  r->SetEnumValue(h, d->FindFieldByName("type"), type);
  r->SetUInt32(h, d->FindFieldByName("schema_version"), msgs::kSchemaVersion);
  r->SetString(h, d->FindFieldByName("publisher"), publisher);
  return msg;
}

void StampHeader(gpb::Message* msg, uint64_t seq, uint64_t request_id) {
  gpb::Message* h = MutableHeader(msg);
  const gpb::Reflection* r = h->GetReflection();
  const gpb::Descriptor* d = h->GetDescriptor();
  const auto now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count();
  r->SetUInt64(h, d->FindFieldByName("seq"), seq);
  if (request_id > 0) r->SetUInt64(h, d->FindFieldByName("request_id"), request_id);
  const gpb::FieldDescriptor* stamp = d->FindFieldByName("publish_stamp_ns");
  if (stamp->cpp_type() == gpb::FieldDescriptor::CPPTYPE_INT64)
    r->SetInt64(h, stamp, now);
  else
    r->SetUInt64(h, stamp, static_cast<uint64_t>(now));
  const gpb::FieldDescriptor* cap = d->FindFieldByName("capture_stamp_ns");
  if (cap != nullptr && r->HasField(*h, cap) == false) {
    if (cap->cpp_type() == gpb::FieldDescriptor::CPPTYPE_INT64)
      r->SetInt64(h, cap, now);
    else
      r->SetUInt64(h, cap, static_cast<uint64_t>(now));
  }
}

}  // namespace p2i::tools
