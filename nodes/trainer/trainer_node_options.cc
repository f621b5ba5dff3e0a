/// @file trainer_node_options.cc
/// @brief The trainer node's parameters -> TrainerNodeOptions, and their validation.
#include "nodes/trainer/trainer_node_options.h"

#include <cmath>

#include <yaml-cpp/yaml.h>

#include "model/distributed.h"
#include "nodes/runtime/option_error.h"

namespace p2i::trainer {
namespace {

void DeclareLoop(runtime::Parameters& p, TrainingLoop::Options* o) {
  o->warm_start = p.Declare<std::string>("checkpoint", o->warm_start,
                                         "warm-start checkpoint (copied into work_dir)");
  o->steps_per_round = p.Declare<int>("publish_every_steps", o->steps_per_round,
                                      "training steps per round/version");
  o->enet_steps_per_round = p.Declare<int>(
      "enet_steps_per_version", o->enet_steps_per_round,
      "ENET steps per round after the G+D steps (-1 = publish_every_steps, 0 = train G only)");
  o->threads = p.Declare<int>("threads", o->threads, "torch threads for training");
  o->max_val_frames = p.Declare<int>("max_val_frames", o->max_val_frames,
                                     "held-out frames for validation PSNR");
  o->max_rounds =
      p.Declare<int>("max_rounds", o->max_rounds, "stop training after N rounds (-1 = never)");
  model::DistributedOptions& d = o->distributed;
  d.world_size = p.Declare<int>("world_size", d.world_size,
                                "data-parallel trainer processes (1 = this one only)");
  d.rank = p.Declare<int>("rank", d.rank, "this process's rank, 0..world_size-1 (0 publishes)");
  d.master = p.Declare<std::string>("master", d.master,
                                    "HOST:PORT of rank 0's rendezvous (world_size > 1)");
  d.address = p.Declare<std::string>(
      "dist_address", d.address,
      "this rank's address for Gloo; empty = 127.0.0.1 for a loopback master, else the host's");
  d.timeout_s = p.Declare<double>("dist_timeout", d.timeout_s,
                                  "s: rendezvous and every collective of the ranks");
}

void DeclareMapper(runtime::Parameters& p, FusionMapperOptions* o) {
  const YAML::Node scene = p.Declare<YAML::Node>(
      "fusion_options", YAML::Node(),
      "method fusion: {tsdf: {...}, blend: {...}} as for the fusion method (fusion/tsdf_volume.h, fusion/fusion_scene.h)");
  if (scene.IsDefined() && !scene.IsNull()) {
    // A launch file's quoted "{tsdf: ...}" arrives as a string; a command line's as a map.
    const YAML::Node map = scene.IsScalar() ? YAML::Load(scene.as<std::string>()) : scene;
    try {
      o->scene = fusion::FusionSceneOptions::FromYaml(map, "trainer parameter fusion_options");
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(e.what());
    }
  }
  o->publish_every_frames = p.Declare<int>(
      "publish_every_frames", o->publish_every_frames,
      "method fusion: integrated frames between published versions");
  o->keep_versions = p.Declare<int>("keep_versions", o->keep_versions,
                                    "method fusion: committed versions kept on disk");
  o->keep_seconds = p.Declare<double>(
      "keep_seconds", o->keep_seconds,
      "method fusion: no version is pruned before it is this old (readers still loading it)");
  o->queue_frames = p.Declare<int>(
      "queue_frames", o->queue_frames,
      "method fusion: frames waiting for integration (older ones are dropped, counted)");
  o->refine_net = p.Declare<std::string>(
      "refine_net", o->refine_net,
      "method fusion: refinement file copied into every version ('' = plain blend)");
  o->refine_finetune_steps = p.Declare<int>(
      "refine_finetune_steps", o->refine_finetune_steps,
      "method fusion: > 0 fine-tunes the refinement (refine_net, or a fresh net) online, this "
      "many Adam steps per version on the newest keyframes (0 = refine_net as it is)");
  o->refine_window_keyframes = p.Declare<int>(
      "refine_window_keyframes", o->refine_window_keyframes,
      "method fusion: the newest keyframes a fine-tuning round renders leave-one-out");
  o->refine_view_width = p.Declare<int>(
      "refine_view_width", o->refine_view_width,
      "method fusion: fine-tuning samples are rendered at the camera scaled to this width");
}

}  // namespace

TrainerNodeOptions TrainerNodeOptions::FromParameters(runtime::Parameters& p) {
  TrainerNodeOptions o;  // the defaults, written once in the field initialisers
  o.method = p.Declare<std::string>(
      "method", o.method,
      "p2i (train the config's network) or fusion (map online: TSDF + keyframes, versions)");
  DeclareMapper(p, &o.mapper);
  o.config_file = p.Declare<std::string>("config", o.config_file,
                                         "P2I-NET config YAML (model/presets/); empty = defaults");
  o.resolution = p.Declare<int>("resolution", o.resolution,
                                "override the config's resolution (0 = keep)");
  o.dataset = p.Declare<std::string>("dataset", o.dataset,
                                     "offline: dataset folder to train on; empty = online");
  o.work_dir = p.Declare<std::string>(
      "work_dir", o.work_dir,
      "checkpoints, versions and the buffer; empty = $P2I_RUN_DIR/<node name>");
  o.buffer.max_mb =
      p.Declare<double>("buffer_mb", o.buffer.max_mb, "replay buffer bound (MiB)");
  o.buffer.recent_fraction = p.Declare<double>("recent_fraction", o.buffer.recent_fraction,
                                               "share of the buffer kept as the recent window");
  o.min_frames =
      p.Declare<int>("min_frames", o.min_frames, "frames needed before training starts");
  DeclareLoop(p, &o.loop);
  o.trainer_status_period = p.Declare<double>("trainer_status_period", o.trainer_status_period,
                                              "s between TrainerStatus messages");
  o.shutdown_wait = p.Declare<double>(
      "shutdown_wait", o.shutdown_wait,
      "s after which a shutdown still waiting for the training step logs it");
  return o;
}

void TrainerNodeOptions::Validate() const {
  using runtime::CheckOption;
  const char* n = "trainer";
  CheckOption(method == "p2i" || method == "fusion", n, "method", method,
              "be p2i or fusion", "method:=p2i trains P2I-NET, method:=fusion maps online");
  if (method == "fusion") {
    CheckOption(loop.distributed.world_size == 1, n, "world_size", loop.distributed.world_size,
                "be 1 with method fusion", "one mapper per camera: world_size:=1");
    CheckOption(mapper.publish_every_frames >= 1, n, "publish_every_frames",
                mapper.publish_every_frames, "be >= 1", "e.g. publish_every_frames:=30");
    CheckOption(mapper.keep_versions >= 1, n, "keep_versions", mapper.keep_versions, "be >= 1",
                "e.g. keep_versions:=3");
    CheckOption(mapper.keep_seconds >= 0.0 && std::isfinite(mapper.keep_seconds), n, "keep_seconds",
                mapper.keep_seconds, "be finite and >= 0", "e.g. keep_seconds:=10");
    CheckOption(mapper.queue_frames >= 1, n, "queue_frames", mapper.queue_frames, "be >= 1",
                "e.g. queue_frames:=2");
    CheckOption(mapper.refine_finetune_steps >= 0, n, "refine_finetune_steps",
                mapper.refine_finetune_steps, "be >= 0", "e.g. refine_finetune_steps:=100");
    CheckOption(mapper.refine_window_keyframes >= 2, n, "refine_window_keyframes",
                mapper.refine_window_keyframes, "be >= 2", "e.g. refine_window_keyframes:=48");
    CheckOption(mapper.refine_view_width >= 16, n, "refine_view_width", mapper.refine_view_width,
                "be >= 16", "e.g. refine_view_width:=160");
  }
  CheckOption(resolution >= 0, n, "resolution", resolution, "be >= 0",
              "resolution:=0 keeps the config's");
  CheckOption(buffer.max_mb > 0.0, n, "buffer_mb", buffer.max_mb, "be > 0", "e.g. buffer_mb:=256");
  CheckOption(buffer.recent_fraction > 0.0 && buffer.recent_fraction <= 1.0, n,
              "recent_fraction", buffer.recent_fraction, "be in (0, 1]",
              "e.g. recent_fraction:=0.5");
  CheckOption(min_frames >= 2, n, "min_frames", min_frames, "be >= 2",
              "training needs a frame to train on and one to validate, e.g. min_frames:=8");
  CheckOption(loop.steps_per_round >= 1, n, "publish_every_steps", loop.steps_per_round,
              "be >= 1", "e.g. publish_every_steps:=200");
  CheckOption(loop.enet_steps_per_round >= -1, n, "enet_steps_per_version",
              loop.enet_steps_per_round, "be >= -1",
              "-1 = publish_every_steps, 0 = train G only");
  CheckOption(loop.threads >= 1, n, "threads", loop.threads, "be >= 1", "e.g. threads:=1");
  CheckOption(loop.max_val_frames >= 1, n, "max_val_frames", loop.max_val_frames, "be >= 1",
              "e.g. max_val_frames:=8");
  CheckOption(loop.max_rounds >= -1, n, "max_rounds", loop.max_rounds, "be >= -1",
              "max_rounds:=-1 trains until stopped");
  const model::DistributedOptions& d = loop.distributed;
  CheckOption(d.world_size >= 1, n, "world_size", d.world_size, "be >= 1",
              "world_size:=1 trains in this process only");
  CheckOption(d.rank >= 0 && d.rank < d.world_size, n, "rank", d.rank,
              "be in [0, " + std::to_string(d.world_size - 1) + "] for world_size " +
                  std::to_string(d.world_size),
              "one rank per trainer process, rank:=0 on the master's host");
  CheckOption(d.world_size == 1 || model::IsHostPort(d.master), n, "master", d.master,
              "be HOST:PORT when world_size > 1",
              "rank 0's address and a free port, the same on every rank, e.g. "
              "master:=127.0.0.1:29500");
  CheckOption(d.timeout_s > 0.0, n, "dist_timeout", d.timeout_s, "be > 0",
              "seconds, e.g. dist_timeout:=60");
  CheckOption(trainer_status_period >= 0.0, n, "trainer_status_period", trainer_status_period,
              "be >= 0", "seconds; 0 = no periodic TrainerStatus");
  CheckOption(shutdown_wait >= 0.0, n, "shutdown_wait", shutdown_wait, "be >= 0",
              "seconds, e.g. shutdown_wait:=2");
}

TrainingLoop::Options TrainerNodeOptions::Loop() const {
  TrainingLoop::Options o = loop;
  o.min_frames = static_cast<size_t>(min_frames);
  return o;
}

}  // namespace p2i::trainer
