/// @file checkpoint.cc
/// @brief Checkpoint file IO (see checkpoint.h).
#include "model/checkpoint.h"

#include "model/checkpoint_integrity.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include <ATen/CPUGeneratorImpl.h>
#include <nlohmann/json.hpp>

namespace p2i::model {

namespace {

using nlohmann::json;

json CameraToJson(const scene::CameraInfo& c) {
  return json{{"name", c.camera_name},
              {"width", c.image_width},
              {"height", c.image_height},
              {"K", c.camera_matrix},
              {"P", c.projection_matrix}};
}

scene::CameraInfo CameraFromJson(const json& j) {
  scene::CameraInfo c;
  c.camera_name = j.at("name").get<std::string>();
  c.image_width = j.at("width").get<int>();
  c.image_height = j.at("height").get<int>();
  c.camera_matrix = j.at("K").get<std::array<double, 9>>();
  c.projection_matrix = j.at("P").get<std::array<double, 12>>();
  c.distortion_coefficients.assign(5, 0.0);
  return c;
}

void SaveModule(torch::serialize::OutputArchive& root, const std::string& key,
                const std::shared_ptr<torch::nn::Module>& module) {
  if (!module) return;
  torch::serialize::OutputArchive sub;
  module->save(sub);
  root.write(key, sub);
}

void SaveModule(torch::serialize::OutputArchive& root, const std::string& key,
                const std::shared_ptr<torch::nn::Module>& module,
                std::map<std::string, int64_t>* manifest) {
  if (!module) return;
  SaveModule(root, key, module);
  AddToManifest(key, *module, manifest);
}

// A checkpoint file read and verified (CRC, size) and opened as a LibTorch archive.
struct OpenedCheckpoint {
  CheckpointPayload payload;
  torch::serialize::InputArchive archive;
};

void OpenCheckpoint(const std::string& path, OpenedCheckpoint* out) {
  if (!std::filesystem::exists(path))
    throw std::runtime_error("checkpoint " + path + " does not exist");
  out->payload = ReadCheckpointPayload(path, kCheckpointFormatVersion);
  try {
    out->archive.load_from(out->payload.bytes.data(), out->payload.bytes.size());
  } catch (const c10::Error& e) {
    throw std::runtime_error("checkpoint " + path + " refused: not a readable LibTorch archive: " +
                             e.what_without_backtrace());
  }
}

void LoadModule(OpenedCheckpoint& file, const std::string& key,
                const std::shared_ptr<torch::nn::Module>& module, const std::string& path) {
  if (!module) return;
  LoadModuleChecked(file.archive, key, *module, path, file.payload.manifest);
}

bool HasModule(OpenedCheckpoint& file, const std::string& key) {
  torch::serialize::InputArchive sub;
  return file.archive.try_read(key, sub);
}

void SaveOptimizer(torch::serialize::OutputArchive& root, const std::string& key,
                   torch::optim::Adam* opt) {
  if (opt == nullptr) return;
  torch::serialize::OutputArchive sub;
  opt->save(sub);
  root.write(key, sub);
}

void LoadOptimizer(torch::serialize::InputArchive& root, const std::string& key,
                   torch::optim::Adam* opt) {
  if (opt == nullptr) return;
  torch::serialize::InputArchive sub;
  // A checkpoint written before this optimiser took a step has no state for it: keep it fresh.
  if (root.try_read(key, sub)) opt->load(sub);
}

}  // namespace

std::string CheckpointMeta::ToJson() const {
  json j;
  j["format_version"] = format_version;
  j["config_yaml"] = config.ToYamlString();
  j["resolution"] = config.resolution;
  j["channels"] = config.Channels();
  j["depth_max"] = config.depth_max;
  j["pose_t_min"] = normalizer.t_min;
  j["pose_t_max"] = normalizer.t_max;
  j["pose_q_ref"] = normalizer.q_ref;
  j["camera"] = CameraToJson(camera);
  j["phase1_step"] = phase1_step;
  j["phase2_step"] = phase2_step;
  j["lr_scale"] = lr_scale;
  j["rollbacks"] = rollbacks;
  j["kind"] = inference_only ? "inference" : "full";
  return j.dump(2);
}

CheckpointMeta CheckpointMeta::FromJson(const std::string& text, const std::string& source) {
  CheckpointMeta m;
  try {
    const json j = json::parse(text);
    m.format_version = j.at("format_version").get<int>();
    if (m.format_version != kCheckpointFormatVersion && m.format_version != 1)
      return m;  // the caller refuses it
    m.config = P2iConfig::FromYamlString(j.at("config_yaml").get<std::string>(), source);
    m.normalizer.t_min = j.at("pose_t_min").get<std::array<double, 3>>();
    m.normalizer.t_max = j.at("pose_t_max").get<std::array<double, 3>>();
    // Absent in checkpoints written before it: identity, the qw >= 0 sign they were trained on.
    if (j.contains("pose_q_ref"))
      m.normalizer.q_ref = j.at("pose_q_ref").get<std::array<double, 4>>();
    m.camera = CameraFromJson(j.at("camera"));
    m.phase1_step = j.at("phase1_step").get<int>();
    m.phase2_step = j.at("phase2_step").get<int>();
    m.lr_scale = j.at("lr_scale").get<double>();
    m.rollbacks = j.at("rollbacks").get<int>();
    const std::string kind = j.value("kind", std::string("full"));
    if (kind != "full" && kind != "inference")
      throw std::runtime_error("checkpoint " + source + ": unknown kind '" + kind +
                               "' (expected full or inference)");
    m.inference_only = kind == "inference";
  } catch (const json::exception& e) {
    throw std::runtime_error("checkpoint " + source + ": bad metadata: " + e.what());
  }
  return m;
}

Networks::Networks(const P2iConfig& config, bool with_discriminator) {
  g = Generator(config);
  if (!config.IsBaseline()) {
    if (with_discriminator) d = Discriminator(config);
    if (config.enet) e = Enhancer(config);
    if (config.g_ema > 0) {  // made last: the other modules' initialisation is unchanged
      g_ema = Generator(config);
      CopyWeights(*g, *g_ema);
      for (auto& p : g_ema->parameters()) p.set_requires_grad(false);
    }
  }
}

void CopyWeights(torch::nn::Module& from, torch::nn::Module& to) {
  torch::NoGradGuard no_grad;
  auto pf = from.named_parameters(), bf = from.named_buffers();
  for (auto& kv : to.named_parameters()) kv.value().copy_(pf[kv.key()]);
  for (auto& kv : to.named_buffers()) kv.value().copy_(bf[kv.key()]);
}

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temp_path)>& writer) {
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  try {
    writer(temp);
  } catch (...) {
    std::remove(temp.c_str());
    throw;
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::remove(temp.c_str());
    throw std::runtime_error("cannot rename " + temp + " to " + path + ": " + ec.message());
  }
}

void SaveCheckpoint(const std::string& path, const CheckpointMeta& meta, Networks& nets,
                    const Optimizers& optimizers) {
  torch::serialize::OutputArchive archive;
  std::map<std::string, int64_t> manifest;
  archive.write("meta", c10::IValue(meta.ToJson()));
  if (!meta.inference_only) {
    SaveModule(archive, "G", nets.g.ptr(), &manifest);
    if (nets.g_ema) SaveModule(archive, "G_EMA", nets.g_ema.ptr(), &manifest);
  } else {
    SaveModule(archive, "G", nets.Serving().ptr(), &manifest);  // the G that renders
  }
  if (nets.e) SaveModule(archive, "ENET", nets.e.ptr(), &manifest);
  if (!meta.inference_only) {
    if (nets.d) SaveModule(archive, "D", nets.d.ptr(), &manifest);
    SaveOptimizer(archive, "opt_G", optimizers.g);
    SaveOptimizer(archive, "opt_D", optimizers.d);
    SaveOptimizer(archive, "opt_ENET", optimizers.e);
    auto gen = at::detail::getDefaultCPUGenerator();
    archive.write("rng_state", gen.get_state());
  }
  std::string zip;
  try {
    archive.save_to([&zip](const void* data, size_t size) {
      zip.append(static_cast<const char*>(data), size);
      return size;
    });
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot serialise checkpoint " + path + ": " + e.what_without_backtrace());
  }
  // Format 2: a header line with the payload's size, CRC-32 and tensor manifest, then the zip
  // (checkpoint_integrity.h). The header's version is meta.format_version (tests write others).
  const std::string bytes = EncodeCheckpointFile(meta.format_version, zip, manifest);
  WriteFileAtomically(path, [&](const std::string& temp) {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) throw std::runtime_error("cannot write checkpoint " + temp + " (disk full?)");
    out.close();
    if (!out) throw std::runtime_error("cannot write checkpoint " + temp + " (disk full?)");
  });
}

namespace {

CheckpointMeta MetaOf(OpenedCheckpoint& file, const std::string& path) {
  c10::IValue meta_value;
  try {
    if (!file.archive.try_read("meta", meta_value) || !meta_value.isString())
      throw std::runtime_error("checkpoint " + path + " has no metadata: not a p2i checkpoint");
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot read checkpoint " + path + ": " + e.what_without_backtrace());
  }
  CheckpointMeta meta = CheckpointMeta::FromJson(meta_value.toStringRef(), path);
  // Format 1 files (the bare zip) say 1 in their metadata; format 2 files say 2 in both.
  const int expected = file.payload.container_version == 1 ? 1 : kCheckpointFormatVersion;
  if (meta.format_version != expected)
    throw std::runtime_error("checkpoint " + path + " has format version " +
                             std::to_string(meta.format_version) + " but this build reads version " +
                             std::to_string(kCheckpointFormatVersion) +
                             " (and 1): retrain it with this build (p2i train) or use the p2i "
                             "build that wrote it");
  // In memory the metadata describes the weights, not the file they came from: a format-1 file
  // (e.g. the shipped demo model used for a warm start) is saved again as the current format.
  meta.format_version = kCheckpointFormatVersion;
  return meta;
}

}  // namespace

CheckpointMeta ReadCheckpointMeta(const std::string& path) {
  OpenedCheckpoint file;
  OpenCheckpoint(path, &file);
  return MetaOf(file, path);
}

CheckpointMeta LoadCheckpoint(const std::string& path, Networks& nets,
                              const Optimizers& optimizers, bool restore_rng) {
  OpenedCheckpoint file;
  OpenCheckpoint(path, &file);
  CheckpointMeta meta = MetaOf(file, path);
  if (meta.inference_only)
    throw std::runtime_error("checkpoint " + path + " is an inference checkpoint (p2i export): it "
                             "has no discriminator, optimiser or RNG state to resume from; use it "
                             "for rendering or as a warm start (p2i train --init-from)");
  try {
    LoadModule(file, "G", nets.g.ptr(), path);
    if (nets.g_ema) LoadModule(file, "G_EMA", nets.g_ema.ptr(), path);
    if (nets.d) LoadModule(file, "D", nets.d.ptr(), path);
    if (nets.e) LoadModule(file, "ENET", nets.e.ptr(), path);
    LoadOptimizer(file.archive, "opt_G", optimizers.g);
    LoadOptimizer(file.archive, "opt_D", optimizers.d);
    LoadOptimizer(file.archive, "opt_ENET", optimizers.e);
    if (restore_rng) {
      torch::Tensor state;
      file.archive.read("rng_state", state);
      auto gen = at::detail::getDefaultCPUGenerator();
      gen.set_state(state);
    }
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot load checkpoint " + path + ": " + e.what_without_backtrace() +
                             " (was it written for another config?)");
  }
  return meta;
}

CheckpointMeta LoadWeights(const std::string& path, Networks& nets, bool with_enet) {
  OpenedCheckpoint file;
  OpenCheckpoint(path, &file);
  CheckpointMeta meta = MetaOf(file, path);
  try {
    LoadModule(file, "G", nets.g.ptr(), path);
    if (nets.g_ema) {
      if (HasModule(file, "G_EMA"))
        LoadModule(file, "G_EMA", nets.g_ema.ptr(), path);
      else
        CopyWeights(*nets.g, *nets.g_ema);
    }
    if (nets.e && with_enet) LoadModule(file, "ENET", nets.e.ptr(), path);
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot load checkpoint " + path + ": " + e.what_without_backtrace() +
                             " (was it written for another config?)");
  }
  return meta;
}

CheckpointMeta LoadServingWeights(const std::string& path, Networks& nets) {
  OpenedCheckpoint file;
  OpenCheckpoint(path, &file);
  CheckpointMeta meta = MetaOf(file, path);
  try {
    LoadModule(file, HasModule(file, "G_EMA") ? "G_EMA" : "G", nets.g.ptr(), path);
    if (nets.e) LoadModule(file, "ENET", nets.e.ptr(), path);
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot load checkpoint " + path + ": " + e.what_without_backtrace() +
                             " (was it written for another config?)");
  }
  return meta;
}

}  // namespace p2i::model
