/// @file batch_sampler.cc
/// @brief Which training frames a step's batch holds (batch_sampler.h).

#include "model/batch_sampler.h"

#include <random>

namespace p2i::model {

namespace {

std::mt19937_64 BatchRng(const BatchDraw& d) {
  return std::mt19937_64(d.seed * 1000003ULL + static_cast<uint64_t>(d.phase) * 7919ULL +
                         static_cast<uint64_t>(d.step));
}

// The global batch's slice that belongs to rank d.rank.
std::vector<int64_t> RankSlice(std::vector<int64_t> global, const BatchDraw& d) {
  global.erase(global.begin(), global.begin() + static_cast<std::ptrdiff_t>(d.rank) * d.batch_size);
  global.resize(static_cast<size_t>(d.batch_size));
  return global;
}

}  // namespace

std::vector<int64_t> DrawBatch(const BatchDraw& d, int64_t n) {
  std::mt19937_64 rng = BatchRng(d);
  std::uniform_int_distribution<int64_t> pick(0, n - 1);
  std::vector<int64_t> idx(static_cast<size_t>(d.batch_size) * d.world);
  for (auto& i : idx) i = pick(rng);
  return RankSlice(std::move(idx), d);
}

std::vector<int64_t> DrawMixedBatch(const BatchDraw& d, const std::vector<int64_t>& captured,
                                    const std::vector<int64_t>& densified, double real_share) {
  if (real_share <= 0 || captured.empty() || densified.empty())
    return DrawBatch(d, static_cast<int64_t>(captured.size() + densified.size()));
  std::mt19937_64 rng = BatchRng(d);
  std::bernoulli_distribution real(real_share);
  std::uniform_int_distribution<size_t> pick_c(0, captured.size() - 1), pick_d(0, densified.size() - 1);
  std::vector<int64_t> idx(static_cast<size_t>(d.batch_size) * d.world);
  for (auto& i : idx) i = real(rng) ? captured[pick_c(rng)] : densified[pick_d(rng)];
  return RankSlice(std::move(idx), d);
}

}  // namespace p2i::model
