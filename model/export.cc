/// @file export.cc
/// @brief ExportInference: a training checkpoint -> the inference checkpoint (G + ENET + meta).
#include "model/export.h"

#include <filesystem>

#include "model/checkpoint.h"
#include "model/networks.h"

namespace p2i::model {

ExportReport ExportInference(const std::string& in_checkpoint, const std::string& out_path) {
  CheckpointMeta meta = ReadCheckpointMeta(in_checkpoint);
  P2iConfig plain = meta.config;
  plain.g_ema = 0.0;  // the exported G is the serving one (the average when there is one)
  Networks nets(plain, /*with_discriminator=*/false);
  LoadServingWeights(in_checkpoint, nets);
  meta.inference_only = true;
  SaveCheckpoint(out_path, meta, nets, {});
  ExportReport r;
  r.in_bytes = static_cast<int64_t>(std::filesystem::file_size(in_checkpoint));
  r.out_bytes = static_cast<int64_t>(std::filesystem::file_size(out_path));
  r.parameters = CountParameters(*nets.g) + (nets.e ? CountParameters(*nets.e) : 0);
  r.phase1_steps = meta.phase1_step;
  r.phase2_steps = meta.phase2_step;
  return r;
}

}  // namespace p2i::model
