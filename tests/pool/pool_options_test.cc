/// @file pool_options_test.cc
/// @brief PoolOptions: the declared defaults are the struct's, parameters override them, every
/// Validate() rule refuses a bad value naming the parameter and showing the value.
#include "nodes/pool/pool_options.h"

#include <catch2/catch.hpp>

#include "tests/option_test_util.h"

namespace p2i::nodes {
namespace {

using namespace p2i::testing;

TEST_CASE("PoolOptions: declared defaults are the field initialisers", "[unit]") {
  const runtime::Parameters p = CheckDefaults<PoolOptions>(6);
  const PoolOptions d;
  CHECK(p.Declared().at("service").default_text == d.service);
  CHECK(p.Declared().at("max_queue").default_text == std::to_string(d.max_queue));
  CHECK(p.Declared().at("worker_timeout").default_text == "3");

  const PoolOptions s =
      OptionsFrom<PoolOptions>({{"worker_timeout", "0.5"}, {"service", "depth"}});
  CHECK(s.worker_timeout == 0.5);
  CHECK(s.service == "depth");
  CHECK_NOTHROW(s.Validate());
}

TEST_CASE("PoolOptions::Validate refuses each bad value, naming parameter and value", "[unit]") {
  CheckRefusals<PoolOptions>(
      "pool", {
                  {{{"service", "''"}}, "service must name a service (got '')"},
                  {{{"worker_timeout", "0"}}, "worker_timeout must be > 0 (got 0)"},
                  {{{"idle_expiry", "-1"}}, "idle_expiry must be > 0 (got -1)"},
                  {{{"max_queue", "0"}}, "max_queue must be > 0 (got 0)"},
              });
}

}  // namespace
}  // namespace p2i::nodes
