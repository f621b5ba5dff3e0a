/// @file checkpoint_swap_test.cc
/// @brief Damaged checkpoints through the synthesizer's real p2i loader: refused at start-up
/// (LoadNow throws naming the file and the reason) and on a hot swap (swap_failures, the error
/// names the file and the reason, the previous version keeps serving).
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include <catch2/catch.hpp>

#include "model/model_profiling.h"
#include "model/p2i_config.h"
#include "convert/pose.h"
#include "nodes/synthesizer/method_loader.h"
#include "nodes/synthesizer/synthesizer_core.h"
#include "tests/checkpoint_tamper.h"
#include "tests/read_file.h"
#include "tests/trainer/trainer_test_util.h"

namespace fs = std::filesystem;

namespace p2i::nodes {

TEST_CASE("damaged checkpoints are refused at synthesizer start-up and on hot swap", "[unit]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_swap_ckpt_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string good = (dir / "good.pt").string();
  model::WriteUntrainedCheckpoint(trainer::testing::TinyConfig(), good);
  const std::string good_bytes = testing::ReadFile(good);
  LoaderOptions lo;
  lo.threads = 1;
  SynthesizerCore core({}, MakeLoader("p2i", lo, nullptr), nullptr);
  core.LoadNow({1, good, "p2i"});
  REQUIRE(core.CurrentVersion() == 1);

  const std::pair<const char*, const char*> damages[] = {
      {"torn", "truncated"},   {"random", "not a p2i checkpoint"},
      {"empty", "empty"},      {"version", "format version 99"},
      {"record", "refused"}, {"nan", "non-finite"},
  };
  uint64_t version = 1;
  uint64_t failures = 0;
  for (const auto& [kind, reason] : damages) {
    INFO(kind);
    const std::string bad = (dir / (std::string(kind) + ".pt")).string();
    testing::WriteBytes(bad, testing::Damaged(good_bytes, kind));
    // Start-up: a fresh core refuses it.
    SynthesizerCore fresh({}, MakeLoader("p2i", lo, nullptr), nullptr);
    CHECK_THROWS_WITH(fresh.LoadNow({0, bad, "p2i"}),
                      Catch::Contains(bad) && Catch::Contains(reason));
    CHECK_FALSE(fresh.HasModel());
    // Hot swap: refused, counted, the serving model stays.
    REQUIRE(core.SwapAsync({++version, bad, "p2i"}));
    ++failures;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (core.Counter("swap_failures") < failures && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    CHECK(core.Counter("swap_failures") == failures);
    CHECK(core.CurrentVersion() == 1);
    CHECK_THAT(core.LastSwapError(), Catch::Contains(bad) && Catch::Contains(reason));
  }
  // A good version after all that still swaps in and renders.
  REQUIRE(core.SwapAsync({++version, good, "p2i"}));
  REQUIRE(core.WaitForVersion(version, std::chrono::seconds(20)));
  msgs::pb::RenderRequest req;
  req.set_request_id(1);
  convert::ToMsg(scene::Pose::Identity(), req.add_poses());
  msgs::RenderReplyMsg reply;
  core.HandleRender(req, SynthesizerCore::Clock::now(), &reply);
  CHECK(reply.meta.ok());
  fs::remove_all(dir);
}

}  // namespace p2i::nodes
