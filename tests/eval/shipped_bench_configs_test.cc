/// @file shipped_bench_configs_test.cc
/// @brief Every bench config the repository ships (bench/configs/**.yaml, the experiment and
/// diagnosis configs that docs/MODEL.md and docs/RESULTS.md quote included) parses, so a
/// command printed in the docs runs as written.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include "eval/bench_config.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using p2i::eval::BenchConfig;

TEST_CASE("Bench configs: every shipped bench/configs/**.yaml parses", "[unit]") {
  const fs::path root = fs::path(p2i::testing::SourceDir()) / "bench" / "configs";
  int count = 0;
  bool saw_diag = false;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (!e.is_regular_file() || e.path().extension() != ".yaml") continue;
    INFO(e.path().string());
    BenchConfig c;
    REQUIRE_NOTHROW(c = BenchConfig::FromYamlFile(e.path().string()));
    CHECK_FALSE(c.methods.empty());
    CHECK_FALSE(c.settings.empty());
    ++count;
    if (e.path().parent_path().filename() == "diag") saw_diag = true;
  }
  CHECK(count >= 10);
  CHECK(saw_diag);
}
