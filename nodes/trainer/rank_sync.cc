/// @file rank_sync.cc
/// @brief RankSync: the round agreements over model/distributed.h's torch-free collectives.
#include "nodes/trainer/rank_sync.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "scene/capture.h"

namespace p2i::trainer {

RoundPoll RankSync::Poll(size_t ready_frames, bool stopping, bool finished) {
  RoundPoll poll;
  if (!Enabled()) {
    poll.frames = ready_frames;
    poll.stopped_rank = stopping ? 0 : -1;
    poll.finished_rank = finished ? 0 : -1;
    return poll;
  }
  // MIN all-reduces: the frames, and each event as the announcing rank (else world_size).
  const int64_t none = WorldSize();
  const int64_t v[3] = {
      model::MinOverRanks(options_, static_cast<int64_t>(ready_frames)),
      model::MinOverRanks(options_, stopping ? Rank() : none),
      model::MinOverRanks(options_, finished ? Rank() : none)};
  poll.frames = static_cast<size_t>(v[0]);
  poll.stopped_rank = v[1] < none ? static_cast<int>(v[1]) : -1;
  poll.finished_rank = v[2] < none ? static_cast<int>(v[2]) : -1;
  return poll;
}

bool RankSync::ShareCheckpoint(const std::string& checkpoint) {
  if (!Enabled()) return true;
  std::string bytes;
  if (IsWriter() && std::filesystem::exists(checkpoint)) {
    std::ifstream in(checkpoint, std::ios::binary);
    if (!in) throw std::runtime_error("rank 0 cannot read its checkpoint " + checkpoint);
    std::ostringstream ss;
    ss << in.rdbuf();
    bytes = ss.str();
    if (bytes.empty()) throw std::runtime_error("rank 0's checkpoint " + checkpoint + " is empty");
  }
  // (A rank 0 that cannot read it has thrown: the others' broadcast then ends in "lost
  // contact" after options.timeout_s.)
  bytes = model::BroadcastFromRankZero(options_, bytes);
  if (bytes.empty()) return false;  // a fresh rank 0: nothing to start from yet
  if (!IsWriter()) scene::WriteFileAtomic(checkpoint, bytes);
  return true;
}

}  // namespace p2i::trainer
