/// @file synthesizer_options_test.cc
/// @brief SynthesizerOptions: the declared defaults are the struct's, parameters override them,
/// Validate() names the parameter and its bad value.
#include "nodes/synthesizer/synthesizer_options.h"

#include <catch2/catch.hpp>

using p2i::nodes::SynthesizerOptions;
using p2i::runtime::Parameters;

TEST_CASE("SynthesizerOptions: declared defaults are the field initialisers", "[unit]") {
  Parameters p;
  const SynthesizerOptions o = SynthesizerOptions::FromParameters(p);
  const SynthesizerOptions d;
  CHECK(o.core.method == d.core.method);
  CHECK(o.width == d.width);
  CHECK(o.loader.threads == d.loader.threads);
  CHECK(o.core.max_poses == d.core.max_poses);
  // Every parameter is declared with a description and the struct's default (what --help shows).
  for (const char* name : {"method", "checkpoint", "dataset", "width", "height", "dataset_stride",
                           "threads", "method_options", "max_poses", "max_batch",
                           "topic_mode"}) {
    INFO(name);
    REQUIRE(p.Declared().count(name) == 1);
    CHECK_FALSE(p.Declared().at(name).description.empty());
    CHECK(p.Declared().at(name).source == "default");
  }
  CHECK(p.Declared().at("max_poses").default_text == std::to_string(d.core.max_poses));
  CHECK(p.Declared().at("dataset").default_text == d.dataset);
  CHECK_NOTHROW(o.Validate());
}

TEST_CASE("SynthesizerOptions: parameters override, Validate shows the bad value", "[unit]") {
  Parameters p;
  p.SetOverride("method", "warp");
  p.SetOverride("width", "160");
  p.SetOverride("height", "120");
  p.SetOverride("method_options", "{k: 2}");
  p.SetOverride("topic_mode", "false");
  const SynthesizerOptions o = SynthesizerOptions::FromParameters(p);
  CHECK(o.core.method == "warp");
  CHECK_FALSE(o.Learned());
  CHECK(SynthesizerOptions().Learned());  // p2i
  CHECK(o.width == 160);
  CHECK(o.height == 120);
  CHECK(o.loader.method_options == "{k: 2}");  // method_options:='{k: 2}' arrives as a map
  Parameters quoted;
  quoted.SetOverride("method_options", "'{k: 2, fill_holes: false}'");  // a launch file's string
  CHECK(SynthesizerOptions::FromParameters(quoted).loader.method_options ==
        "{k: 2, fill_holes: false}");
  CHECK_FALSE(o.topic_mode);
  CHECK_NOTHROW(o.Validate());

  // The error of the default options with one field changed.
  const auto error_of = [](void (*change)(SynthesizerOptions*)) {
    SynthesizerOptions bad;
    change(&bad);
    try {
      bad.Validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error_of([](SynthesizerOptions* b) { b->dataset_stride = 0; }) ==
        "synthesizer: dataset_stride must be >= 1 (got 0); 1 = every frame of the dataset");
  CHECK(error_of([](SynthesizerOptions* b) { b->core.max_poses = 5000; }) ==
        "synthesizer: max_poses must be in [1, 4096] (got 5000)");
  CHECK(error_of([](SynthesizerOptions* b) { b->width = 0; }) ==
        "synthesizer: width and height must both be > 0 or both 0 (got 0x64); set both (resize "
        "the training data) or neither (the dataset's own size)");
  CHECK(error_of([](SynthesizerOptions* b) { b->loader.threads = -1; }) ==
        "synthesizer: threads must be >= 1 (got -1); e.g. threads:=1");
  CHECK(error_of([](SynthesizerOptions* b) { b->core.method = "nerf"; }).find("'nerf'") !=
        std::string::npos);
}
