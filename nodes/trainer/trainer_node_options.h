/// @file trainer_node_options.h
/// @brief Every parameter of the trainer node in one Options struct: defaults in the field
/// initialisers (written once: the replay buffer's and training loop's are theirs), read from
/// the node's parameters in one function, one Validate().
#pragma once

#include <string>

#include "nodes/runtime/parameters.h"
#include "nodes/trainer/fusion_mapper.h"
#include "nodes/trainer/replay_buffer.h"
#include "nodes/trainer/training_loop.h"

namespace p2i::trainer {

/// The trainer node's configuration (docs/TRAINER.md lists the parameters). `buffer` and `loop`
/// carry the parameters that are theirs (buffer_mb -> buffer.max_mb, publish_every_steps ->
/// loop.steps_per_round, checkpoint -> loop.warm_start, world_size / rank / master /
/// dist_address / dist_timeout -> loop.distributed, ...); the node fills in the rest (the
/// model config, work_dir, resolution) when it starts. A value type: thread-compatible.
struct TrainerNodeOptions {
  /// What the node trains: "p2i" (the learned network of `config`: P2I-NET, or the CNN
  /// baseline) or "fusion" (online mapping: FusionMapper; `config`, the buffer and the loop
  /// parameters are not used).
  std::string method = "p2i";
  FusionMapperOptions mapper;  ///< method fusion: fusion_options, publish_every_frames, ...
  std::string config_file;  ///< P2I-NET config YAML (model/presets/); "" = defaults
  int resolution = 0;       ///< overrides the config's resolution; 0 = keep
  std::string dataset;      ///< offline: dataset folder to train on; "" = online ("rgbd")
  std::string work_dir;     ///< checkpoints, versions, buffer; "" = $P2I_RUN_DIR/<node name>
  ReplayBuffer::Options buffer;  ///< max_mb, recent_fraction
  TrainingLoop::Options loop;    ///< steps, threads, max_val_frames, warm_start, distributed...
  /// Frames needed before training starts: loop.min_frames (its default) once validated; an int
  /// here so that Validate() can show a negative value.
  int min_frames = static_cast<int>(TrainingLoop::Options().min_frames);
  double trainer_status_period = 1.0;  ///< s between TrainerStatus messages; 0 = none
  double shutdown_wait = 2.0;  ///< s after which a shutdown still waiting for a step logs it

  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description) and returns the values supplied or the defaults. Throws runtime::StartupError
  /// for a value of the wrong type.
  static TrainerNodeOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter, its bad value and how to fix it.
  void Validate() const;

  /// `loop` with min_frames set (Validate() first).
  TrainingLoop::Options Loop() const;
};

}  // namespace p2i::trainer
