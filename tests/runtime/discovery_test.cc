/// @file discovery_test.cc
/// @brief What `p2i topic` relies on: the registry and the rate statistics.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>

#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/rate_window.h"
#include "nodes/runtime/raw_publisher.h"
#include "tests/runtime/test_util.h"

using namespace p2i::runtime;

TEST_CASE("RateWindow: rate, min, max and std dev of the periods over the window", "[unit]") {
  RateWindow w(3);
  CHECK(w.Summarize().periods == 0);
  for (double t : {0.0, 0.1, 0.3, 0.4, 0.5}) w.Add(t);  // periods .1 .2 .1 .1 -> window .2 .1 .1
  const auto s = w.Summarize();
  CHECK(s.periods == 3);
  CHECK(s.mean_s == Approx(0.4 / 3));
  CHECK(s.rate_hz == Approx(7.5));
  CHECK(s.min_s == Approx(0.1));
  CHECK(s.max_s == Approx(0.2));
  CHECK(s.stddev_s == Approx(std::sqrt(((0.2 - 0.4 / 3) * (0.2 - 0.4 / 3) +
                                        2 * (0.1 - 0.4 / 3) * (0.1 - 0.4 / 3)) / 3)));
}

TEST_CASE("Registry: publishers appear with type and endpoint, vanish on close or death",
          "[unit]") {
  testing::ScopedRunDir run_dir;
  PublisherOptions tcp;
  tcp.endpoint = "tcp://127.0.0.1:*";
  {
    RawPublisher a("/cam/rgbd", "RgbdFrame", "/cam", PublisherOptions{});
    RawPublisher b("/cam/info", "CameraInfo", "/cam", tcp);
    const auto list = Registry::List();
    REQUIRE(list.size() == 2);
    CHECK(list[0].name == "/cam/info");  // sorted
    CHECK(list[0].endpoint == b.Endpoint());
    CHECK(list[0].endpoint.find(":*") == std::string::npos);  // the real port
    CHECK(list[1].type == "RgbdFrame");
    CHECK(list[1].node == "/cam");
    CHECK(list[1].pid == getpid());
  }
  CHECK(Registry::List().empty());

  // An entry left behind by a process that died without cleaning up is ignored.
  const pid_t child = fork();
  if (child == 0) {
    Registry::Register({"topic", "/ghost", "PoseStamped", "ipc:///nowhere", "/ghost", 0, "", ""});
    _exit(0);
  }
  waitpid(child, nullptr, 0);
  CHECK(Registry::List().empty());
}
