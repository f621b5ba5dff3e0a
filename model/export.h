/// @file export.h
/// @brief `p2i export`'s core: the small inference checkpoint (G + ENET + metadata) written from
/// a training checkpoint. Torch-free header.
#pragma once

#include <cstdint>
#include <string>

namespace p2i::model {

/// What ExportInference wrote.
struct ExportReport {
  int64_t in_bytes = 0;
  int64_t out_bytes = 0;
  int64_t parameters = 0;  ///< G + ENET
  int phase1_steps = 0;
  int phase2_steps = 0;
};

/// Writes an inference checkpoint (atomically): the metadata (format version, config, pose
/// normalisation, resolution, camera, steps) with G and ENET only; no D, optimiser or RNG state.
/// LoadSynthesizer renders it exactly like the full checkpoint, and Trainer can warm-start from
/// it (TrainerOptions::init_from). Throws std::runtime_error naming the file on a missing input,
/// another format version or a write failure.
ExportReport ExportInference(const std::string& in_checkpoint, const std::string& out_path);

}  // namespace p2i::model
