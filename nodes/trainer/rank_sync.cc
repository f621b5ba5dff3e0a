/// @file rank_sync.cc
/// @brief RankSync: the round agreements over model/distributed.h's torch-free collectives.
#include "nodes/trainer/rank_sync.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "scene/capture.h"

namespace p2i::trainer {

size_t RankSync::AgreeFrames(size_t frames) {
  if (!Enabled()) return frames;
  return static_cast<size_t>(model::MinOverRanks(options_, static_cast<int64_t>(frames)));
}

void RankSync::ShareCheckpoint(const std::string& checkpoint) {
  if (!Enabled()) return;
  std::string bytes;
  if (IsWriter()) {
    std::ifstream in(checkpoint, std::ios::binary);
    if (!in) throw std::runtime_error("rank 0 cannot read its checkpoint " + checkpoint);
    std::ostringstream ss;
    ss << in.rdbuf();
    bytes = ss.str();
  }
  // (A rank 0 that cannot read it has thrown: the others' broadcast then ends in "lost
  // contact" after options.timeout_s.)
  bytes = model::BroadcastFromRankZero(options_, bytes);
  if (IsWriter()) return;
  if (bytes.empty())
    throw std::runtime_error("rank " + std::to_string(Rank()) +
                             " received an empty checkpoint from rank 0");
  scene::WriteFileAtomic(checkpoint, bytes);
}

}  // namespace p2i::trainer
