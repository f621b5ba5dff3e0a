/// @file tiny_config.h
/// @brief The tiny P2I-NET config the model, trainer and tool tests train for a few steps.
/// Torch-free (model/p2i_config.h only).
#pragma once

#include <string>

#include "model/p2i_config.h"

namespace p2i::testing {

/// A 32x32 model small enough to train a few steps in about a second on one core. `model` is
/// "p2i_net" or "cnn_baseline".
inline model::P2iConfig TinyConfig(const std::string& model = "p2i_net") {
  model::P2iConfig c;
  c.name = model == "p2i_net" ? "tiny" : "tiny_" + model;
  c.model = model;
  c.resolution = 32;
  c.g_schedule = "custom";
  c.g_widths = {16, 16, 8, 8};
  c.g_fc_width = 16;
  c.d_base_width = 8;
  c.d_max_width = 16;
  c.latent_dim = 32;
  c.mapping_width = 16;
  c.enet_width = 8;
  c.enet_blocks = 1;
  c.batch_size = 4;
  c.val_every = 5;
  c.checkpoint_every = 3;
  c.Validate();
  return c;
}

}  // namespace p2i::testing
