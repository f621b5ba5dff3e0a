/// @file checkpoint_integrity.cc
/// @brief Checkpoint container (format 2), CRC-32, tensor manifest and loaded-tensor checks.
#include "model/checkpoint_integrity.h"

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace p2i::model {
namespace {

using nlohmann::json;

constexpr const char* kMagic = "P2ICKPT ";
constexpr size_t kMaxHeaderBytes = 64 << 20;  // the manifest of a big model is well under this

std::array<uint32_t, 256> MakeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

std::string Hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%08x", v);
  return buf;
}

std::string FirstBytes(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size() && i < 8; ++i) {
    char buf[8];
    std::snprintf(buf, sizeof(buf), "%s%02x", i ? " " : "", static_cast<unsigned char>(s[i]));
    out += buf;
  }
  return out;
}

[[noreturn]] void Refuse(const std::string& path, const std::string& why) {
  throw std::runtime_error("checkpoint " + path + " refused: " + why);
}

}  // namespace

uint32_t Crc32(const void* data, size_t size, uint32_t crc) {
  static const std::array<uint32_t, 256> table = MakeCrcTable();
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

CheckpointPayload ReadCheckpointPayload(const std::string& path, int supported_version) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("checkpoint " + path + " does not exist or cannot be read");
  std::ostringstream buf;
  buf << in.rdbuf();
  std::string file = buf.str();
  CheckpointPayload out;
  if (file.empty()) Refuse(path, "the file is empty (0 bytes): an interrupted write or copy");
  if (file.compare(0, 4, std::string("PK\x03\x04", 4)) == 0) {
    out.container_version = 1;  // a format-1 file: the bare LibTorch zip, no checksum
    out.bytes = std::move(file);
    return out;
  }
  const std::string magic = kMagic;
  if (file.compare(0, magic.size(), magic) != 0) {
    Refuse(path, "not a p2i checkpoint (it starts with bytes " + FirstBytes(file) +
                     "; p2i checkpoints start with 'P2ICKPT' or, written before format 2, "
                     "are a zip starting with 'PK')");
  }
  const size_t nl1 = file.find('\n');
  if (nl1 == std::string::npos || nl1 > 32) Refuse(path, "its first line (format version) is cut short");
  const std::string version_text = file.substr(magic.size(), nl1 - magic.size());
  int version = 0;
  try {
    size_t used = 0;
    version = std::stoi(version_text, &used);
    if (used != version_text.size()) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    Refuse(path, "its first line has no format version number ('" + version_text + "')");
  }
  if (version != supported_version) {
    throw std::runtime_error("checkpoint " + path + " has format version " +
                             std::to_string(version) + " but this build reads version " +
                             std::to_string(supported_version) +
                             " (and 1): retrain it with this build (p2i train) or use the p2i "
                             "build that wrote it");
  }
  const size_t nl2 = file.find('\n', nl1 + 1);
  if (nl2 == std::string::npos) {
    Refuse(path, file.size() - nl1 - 1 > kMaxHeaderBytes
                     ? "its header line is longer than 64 MiB"
                     : "the file ends inside its header line (truncated after " +
                           std::to_string(file.size()) + " bytes)");
  }
  int64_t payload_bytes = -1;
  std::string crc_text;
  try {
    const json header = json::parse(file.begin() + static_cast<long>(nl1) + 1,
                                    file.begin() + static_cast<long>(nl2));
    payload_bytes = header.at("payload_bytes").get<int64_t>();
    crc_text = header.at("payload_crc32").get<std::string>();
    for (const auto& [name, numel] : header.at("tensors").items())
      out.manifest[name] = numel.get<int64_t>();
  } catch (const json::exception& e) {
    Refuse(path, std::string("its header is not valid: ") + e.what());
  }
  const int64_t have = static_cast<int64_t>(file.size() - nl2 - 1);
  if (have < payload_bytes) {
    Refuse(path, "truncated: the payload has " + std::to_string(have) + " of its " +
                     std::to_string(payload_bytes) + " bytes (an interrupted write or copy)");
  }
  if (have > payload_bytes) {
    Refuse(path, std::to_string(have - payload_bytes) + " unexpected bytes after the " +
                     std::to_string(payload_bytes) + "-byte payload");
  }
  const uint32_t crc = Crc32(file.data() + nl2 + 1, static_cast<size_t>(payload_bytes));
  if (Hex32(crc) != crc_text) {
    Refuse(path, "corrupted: the payload's CRC-32 is " + Hex32(crc) + " but the header says " +
                     crc_text + " (a damaged copy or disk; use another copy)");
  }
  out.container_version = version;
  out.bytes = file.substr(nl2 + 1);
  return out;
}

std::string EncodeCheckpointFile(int version, const std::string& archive_bytes,
                                 const std::map<std::string, int64_t>& manifest) {
  json header;
  header["payload_bytes"] = static_cast<int64_t>(archive_bytes.size());
  header["payload_crc32"] = Hex32(Crc32(archive_bytes.data(), archive_bytes.size()));
  header["tensors"] = json::object();
  for (const auto& [name, numel] : manifest) header["tensors"][name] = numel;
  std::string out = std::string(kMagic) + std::to_string(version) + "\n" + header.dump() + "\n";
  out += archive_bytes;
  return out;
}

void AddToManifest(const std::string& key, torch::nn::Module& module,
                   std::map<std::string, int64_t>* manifest) {
  for (const auto& kv : module.named_parameters())
    if (kv.value().defined()) (*manifest)[key + "/" + kv.key()] = kv.value().numel();
  for (const auto& kv : module.named_buffers())
    if (kv.value().defined()) (*manifest)[key + "/" + kv.key()] = kv.value().numel();
}

namespace {

void CheckTensor(const std::string& path, const std::string& name, const torch::Tensor& t,
                 const torch::Tensor& into, const std::map<std::string, int64_t>& manifest) {
  const std::string what = "tensor '" + name + "'";
  if (!manifest.empty()) {
    auto it = manifest.find(name);
    if (it == manifest.end()) Refuse(path, what + " is not in the file's manifest");
    if (it->second != t.numel()) {
      Refuse(path, what + " has " + std::to_string(t.numel()) + " elements but the manifest "
                   "says " + std::to_string(it->second));
    }
  }
  if (t.sizes() != into.sizes()) {
    std::ostringstream msg;
    msg << what << " has shape " << t.sizes() << " but the network built from the file's "
        << "config has " << into.sizes() << " (was it written for another config?)";
    Refuse(path, msg.str());
  }
  if (t.numel() == 0) return;
  // The storage must hold the furthest element the sizes and strides reach.
  int64_t last = t.storage_offset();
  for (int64_t d = 0; d < t.dim(); ++d) last += (t.size(d) - 1) * t.stride(d);
  const int64_t need = (last + 1) * static_cast<int64_t>(t.element_size());
  const int64_t has = static_cast<int64_t>(t.storage().nbytes());
  if (has < need) {
    Refuse(path, what + " needs " + std::to_string(need) + " bytes but its record holds " +
                     std::to_string(has) + " (a record cut short)");
  }
  if (t.is_floating_point()) {
    const auto finite = torch::isfinite(t);
    if (!finite.all().item<bool>()) {
      const int64_t bad = t.numel() - finite.sum().item<int64_t>();
      Refuse(path, what + " has " + std::to_string(bad) + " non-finite value(s) (NaN or inf) of " +
                       std::to_string(t.numel()) + ": a diverged or damaged model");
    }
  }
}

void LoadRecursive(torch::serialize::InputArchive& archive, const std::string& prefix,
                   torch::nn::Module& module, const std::string& path,
                   const std::map<std::string, int64_t>& manifest) {
  torch::NoGradGuard no_grad;
  const auto load_tensor = [&](const std::string& name, torch::Tensor& into, bool is_buffer) {
    if (!into.defined()) return;
    torch::Tensor read;  // undefined: try_read hands over the file's tensor without set_()
    if (!archive.try_read(name, read, is_buffer))
      Refuse(path, "tensor '" + prefix + name + "' is missing (was it written for another config?)");
    CheckTensor(path, prefix + name, read, into, manifest);
    into.copy_(read);
  };
  for (auto& kv : module.named_parameters(/*recurse=*/false)) load_tensor(kv.key(), kv.value(), false);
  for (auto& kv : module.named_buffers(/*recurse=*/false)) load_tensor(kv.key(), kv.value(), true);
  for (auto& kv : module.named_children()) {
    if (!kv.value()->is_serializable()) continue;  // as Module::save / load
    torch::serialize::InputArchive child;
    if (!archive.try_read(kv.key(), child))
      Refuse(path, "module '" + prefix + kv.key() + "' is missing (was it written for another config?)");
    LoadRecursive(child, prefix + kv.key() + ".", *kv.value(), path, manifest);
  }
}

}  // namespace

void LoadModuleChecked(torch::serialize::InputArchive& archive, const std::string& key,
                       torch::nn::Module& module, const std::string& path,
                       const std::map<std::string, int64_t>& manifest) {
  torch::serialize::InputArchive sub;
  if (!archive.try_read(key, sub)) Refuse(path, "module '" + key + "' is missing");
  LoadRecursive(sub, key + "/", module, path, manifest);
}

}  // namespace p2i::model
