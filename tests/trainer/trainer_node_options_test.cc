/// @file trainer_node_options_test.cc
/// @brief TrainerNodeOptions: the declared defaults are the buffer's, loop's and node's field
/// initialisers, parameters override them, every Validate() rule refuses a bad value naming
/// the parameter and showing the value. Torch-free.
#include "nodes/trainer/trainer_node_options.h"

#include <catch2/catch.hpp>

#include "nodes/runtime/option_error.h"
#include "tests/option_test_util.h"

namespace p2i::trainer {
namespace {

using namespace p2i::testing;

TEST_CASE("TrainerNodeOptions: declared defaults are the field initialisers", "[unit]") {
  const runtime::Parameters p = CheckDefaults<TrainerNodeOptions>(30);
  const TrainingLoop::Options loop;
  CHECK(p.Declared().at("buffer_mb").default_text == "256");  // ReplayBuffer::Options'
  CHECK(p.Declared().at("publish_every_steps").default_text ==
        std::to_string(loop.steps_per_round));
  CHECK(p.Declared().at("min_frames").default_text == std::to_string(loop.min_frames));
  CHECK(p.Declared().at("enet_steps_per_version").default_text == "-1");
  CHECK(p.Declared().at("refine_finetune_steps").default_text == "0");  // off unless asked
  CHECK(TrainerNodeOptions().Loop().min_frames == loop.min_frames);
  // One process unless asked: world_size 1 is today's single-process node.
  CHECK(p.Declared().at("world_size").default_text == "1");
  CHECK(p.Declared().at("dist_timeout").default_text ==
        runtime::ShowOptionValue(model::DistributedOptions().timeout_s));
  CHECK_FALSE(TrainerNodeOptions().Loop().distributed.Enabled());

  const TrainerNodeOptions s = OptionsFrom<TrainerNodeOptions>(
      {{"publish_every_steps", "4"}, {"min_frames", "4"}, {"checkpoint", "a.pt"}});
  CHECK(s.loop.steps_per_round == 4);
  CHECK(s.Loop().min_frames == 4);
  CHECK(s.loop.warm_start == "a.pt");
  CHECK_NOTHROW(s.Validate());

  const TrainerNodeOptions r = OptionsFrom<TrainerNodeOptions>(
      {{"world_size", "2"}, {"rank", "1"}, {"master", "10.0.0.1:29500"}, {"dist_timeout", "5"}});
  const model::DistributedOptions& d = r.Loop().distributed;
  CHECK(d.Enabled());
  CHECK(d.rank == 1);
  CHECK(d.master == "10.0.0.1:29500");
  CHECK(d.timeout_s == 5.0);
  CHECK_NOTHROW(r.Validate());
}

TEST_CASE("TrainerNodeOptions::Validate refuses each bad value, naming parameter and value",
          "[unit]") {
  CheckRefusals<TrainerNodeOptions>(
      "trainer",
      {
          {{{"resolution", "-64"}}, "resolution must be >= 0 (got -64)"},
          {{{"buffer_mb", "0"}}, "buffer_mb must be > 0 (got 0)"},
          {{{"recent_fraction", "1.5"}}, "recent_fraction must be in (0, 1] (got 1.5)"},
          {{{"recent_fraction", "0"}}, "recent_fraction must be in (0, 1] (got 0)"},
          {{{"min_frames", "1"}}, "min_frames must be >= 2 (got 1)"},
          {{{"min_frames", "-3"}}, "min_frames must be >= 2 (got -3)"},
          {{{"publish_every_steps", "0"}}, "publish_every_steps must be >= 1 (got 0)"},
          {{{"enet_steps_per_version", "-2"}}, "enet_steps_per_version must be >= -1 (got -2)"},
          {{{"threads", "0"}}, "threads must be >= 1 (got 0)"},
          {{{"max_val_frames", "0"}}, "max_val_frames must be >= 1 (got 0)"},
          {{{"max_rounds", "-5"}}, "max_rounds must be >= -1 (got -5)"},
          {{{"trainer_status_period", "-1"}}, "trainer_status_period must be >= 0 (got -1)"},
          {{{"shutdown_wait", "-0.5"}}, "shutdown_wait must be >= 0 (got -0.5)"},
          {{{"world_size", "0"}}, "world_size must be >= 1 (got 0)"},
          {{{"world_size", "2"}, {"rank", "2"}, {"master", "127.0.0.1:29500"}},
           "rank must be in [0, 1] for world_size 2 (got 2)"},
          {{{"rank", "-1"}}, "rank must be in [0, 0] for world_size 1 (got -1)"},
          {{{"world_size", "2"}}, "master must be HOST:PORT when world_size > 1 (got '')"},
          {{{"world_size", "2"}, {"master", "10.0.0.1"}},
           "master must be HOST:PORT when world_size > 1 (got '10.0.0.1')"},
          {{{"world_size", "2"}, {"master", "10.0.0.1:70000"}},
           "master must be HOST:PORT when world_size > 1 (got '10.0.0.1:70000')"},
          {{{"dist_timeout", "0"}}, "dist_timeout must be > 0 (got 0)"},
          {{{"method", "gan"}}, "method must be p2i or fusion (got 'gan')"},
          {{{"method", "fusion"}, {"publish_every_frames", "0"}},
           "publish_every_frames must be >= 1 (got 0)"},
          {{{"method", "fusion"}, {"keep_versions", "0"}}, "keep_versions must be >= 1 (got 0)"},
          {{{"method", "fusion"}, {"keep_seconds", "-1"}}, "keep_seconds must be finite and >= 0 (got -1)"},
          {{{"method", "fusion"}, {"queue_frames", "0"}}, "queue_frames must be >= 1 (got 0)"},
          {{{"method", "fusion"}, {"refine_finetune_steps", "-1"}},
           "refine_finetune_steps must be >= 0 (got -1)"},
          {{{"method", "fusion"}, {"refine_window_keyframes", "1"}},
           "refine_window_keyframes must be >= 2 (got 1)"},
          {{{"method", "fusion"}, {"refine_view_width", "8"}}, "refine_view_width must be >= 16 (got 8)"},
          {{{"method", "fusion"}, {"world_size", "2"}, {"master", "127.0.0.1:29500"}},
           "world_size must be 1 with method fusion (got 2)"},
      });
}

TEST_CASE("TrainerNodeOptions: method fusion reads the mapper's parameters", "[unit]") {
  const TrainerNodeOptions o = OptionsFrom<TrainerNodeOptions>(
      {{"method", "fusion"},
       {"fusion_options", "{tsdf: {voxel_size_m: 0.04}, blend: {keyframe_min_distance: 0.1}}"},
       {"publish_every_frames", "12"},
       {"keep_versions", "4"},
       {"keep_seconds", "2.5"},
       {"refine_finetune_steps", "50"},
       {"refine_window_keyframes", "24"},
       {"refine_view_width", "128"}});
  CHECK(o.method == "fusion");
  CHECK(o.mapper.scene.tsdf.voxel_size_m == 0.04);
  CHECK(o.mapper.scene.blend.keyframe_min_distance == 0.1);
  CHECK(o.mapper.publish_every_frames == 12);
  CHECK(o.mapper.keep_versions == 4);
  CHECK(o.mapper.keep_seconds == 2.5);
  CHECK(o.mapper.refine_finetune_steps == 50);
  CHECK(o.mapper.refine_window_keyframes == 24);
  CHECK(o.mapper.refine_view_width == 128);
  CHECK_NOTHROW(o.Validate());
  // A bad key in fusion_options stops at start-up, naming the parameter and the key.
  CHECK_THROWS_WITH(OptionsFrom<TrainerNodeOptions>({{"fusion_options", "{tsdf: {voxel: 0.1}}"}}),
                    Catch::Contains("fusion_options") && Catch::Contains("voxel"));
}

}  // namespace
}  // namespace p2i::trainer
