/// @file batch_sampler_test.cc
/// @brief Batch draws: reproducible per (seed, phase, step), ranks slice one global batch, and
/// densify_real_share's mixed draws keep the captured frames' share.
#include <algorithm>
#include <set>

#include <catch2/catch.hpp>

#include "model/batch_sampler.h"

namespace p2i::model {
namespace {

BatchDraw Draw(int step, int batch = 8) {
  BatchDraw d;
  d.seed = 3;
  d.phase = 1;
  d.step = step;
  d.batch_size = batch;
  return d;
}

TEST_CASE("DrawBatch is a pure function of seed, phase and step, in range", "[unit]") {
  const auto a = DrawBatch(Draw(5), 50);
  CHECK(a == DrawBatch(Draw(5), 50));
  CHECK(a != DrawBatch(Draw(6), 50));
  BatchDraw other_phase = Draw(5);
  other_phase.phase = 2;
  CHECK(a != DrawBatch(other_phase, 50));
  REQUIRE(a.size() == 8);
  for (int64_t i : a) CHECK((i >= 0 && i < 50));
}

TEST_CASE("DrawBatch: two ranks' slices are the halves of one global batch", "[unit]") {
  BatchDraw global = Draw(2, 8);
  const auto whole = DrawBatch(global, 40);
  BatchDraw r0 = Draw(2, 4), r1 = Draw(2, 4);
  r0.world = r1.world = 2;
  r1.rank = 1;
  std::vector<int64_t> joined = DrawBatch(r0, 40);
  const auto second = DrawBatch(r1, 40);
  joined.insert(joined.end(), second.begin(), second.end());
  CHECK(joined == whole);
}

TEST_CASE("DrawMixedBatch keeps the captured share and draws from both lists", "[unit]") {
  // Captured and densified interleaved, to show the draw uses the lists, not an index range.
  std::vector<int64_t> captured, densified;
  for (int64_t i = 0; i < 400; ++i) (i % 4 == 0 ? captured : densified).push_back(i);
  const std::set<int64_t> is_captured(captured.begin(), captured.end());
  for (double share : {0.25, 0.5, 0.9}) {
    int real = 0, total = 0;
    std::set<int64_t> seen;
    for (int step = 0; step < 2000; ++step)
      for (int64_t i : DrawMixedBatch(Draw(step), captured, densified, share)) {
        real += is_captured.count(i) ? 1 : 0;
        ++total;
        seen.insert(i);
      }
    CHECK(static_cast<double>(real) / total == Approx(share).margin(0.02));
    CHECK(seen.size() > 390);  // both lists are drawn from across their whole length
  }
  // Uniform over all 400 frames, a quarter of them captured: the share is what the lists give.
  int real = 0;
  for (int step = 0; step < 500; ++step)
    for (int64_t i : DrawBatch(Draw(step), 400)) real += is_captured.count(i) ? 1 : 0;
  CHECK(real / 4000.0 == Approx(0.25).margin(0.03));
  CHECK(DrawMixedBatch(Draw(7), captured, densified, 0.5) ==
        DrawMixedBatch(Draw(7), captured, densified, 0.5));
  // Share 1 (past densify_steps): captured frames only, across the whole list.
  std::set<int64_t> seen_at_1;
  for (int step = 0; step < 500; ++step)
    for (int64_t i : DrawMixedBatch(Draw(step), captured, densified, 1.0)) {
      CHECK(is_captured.count(i) == 1);
      seen_at_1.insert(i);
    }
  CHECK(seen_at_1.size() == captured.size());
}

TEST_CASE("DrawMixedBatch without a share or without densified frames is DrawBatch", "[unit]") {
  std::vector<int64_t> captured(30), none;
  for (int64_t i = 0; i < 30; ++i) captured[static_cast<size_t>(i)] = i;
  std::vector<int64_t> densified = {30, 31, 32};
  CHECK(DrawMixedBatch(Draw(4), captured, none, 0.5) == DrawBatch(Draw(4), 30));
  CHECK(DrawMixedBatch(Draw(4), captured, densified, 0.0) == DrawBatch(Draw(4), 33));
}

}  // namespace
}  // namespace p2i::model
