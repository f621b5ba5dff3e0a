/// @file cmd_export.cc
/// @brief `p2i export CHECKPOINT --out FILE`: writes the small inference checkpoint (G, ENET,
/// config, pose normalisation, camera; no D, optimiser or RNG state) that rendering and warm
/// starts need (model::ExportInference).
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "model/trainer.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunExport(const std::vector<std::string>& args) {
  CLI::App app{"Write a small inference checkpoint (G + ENET + metadata; no discriminator, "
               "optimiser or RNG state) from a training checkpoint. The synthesizer loads it like "
               "the full one; p2i train --init-from warm-starts from it. Written atomically.",
               "p2i export"};
  std::string in_path, out_path;
  app.add_option("checkpoint", in_path, "training checkpoint (e.g. runs/office/checkpoint.pt)")
      ->required();
  app.add_option("--out,-o", out_path, "inference checkpoint to write (e.g. models/office.pt)")
      ->required();
  std::vector<std::string> rev(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const auto parent = std::filesystem::path(out_path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  const model::ExportReport r = model::ExportInference(in_path, out_path);
  std::printf("exported %s -> %s\n%lld parameters (G%s), phase 1 %d steps, phase 2 %d steps\n"
              "%.2f MB -> %.2f MB\n",
              in_path.c_str(), out_path.c_str(), static_cast<long long>(r.parameters),
              r.phase2_steps > 0 ? " + ENET" : "", r.phase1_steps, r.phase2_steps,
              r.in_bytes / 1e6, r.out_bytes / 1e6);
  return 0;
}

P2I_COMMAND("export", "Write a small inference checkpoint (G, ENET, metadata) from a training one",
            RunExport);

}  // namespace
}  // namespace p2i::tools
