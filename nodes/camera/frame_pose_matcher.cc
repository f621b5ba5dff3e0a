/// @file frame_pose_matcher.cc
#include "nodes/camera/frame_pose_matcher.h"

#include <stdexcept>

namespace p2i::nodes {

FramePoseMatcher::FramePoseMatcher(const Options& options)
    : options_(options), poses_(options.pose_capacity) {
  if (options.tolerance_ns < 0 || options.max_wait_ns < 0 || options.max_pending == 0) {
    throw std::invalid_argument(
        "FramePoseMatcher: tolerance and max_wait must be >= 0, max_pending >= 1");
  }
}

void FramePoseMatcher::AddPose(int64_t stamp_ns, const scene::Pose& pose) {
  switch (poses_.Add(stamp_ns, pose)) {
    case scene::PoseStream::AddResult::kAdded: break;
    case scene::PoseStream::AddResult::kDuplicate: ++counters_.poses_duplicate; break;
    case scene::PoseStream::AddResult::kTooOld: ++counters_.poses_too_old; break;
  }
}

void FramePoseMatcher::AddFrame(LiveFrame&& frame, int64_t now_ns) {
  while (pending_.size() >= options_.max_pending) {
    pending_.pop_front();
    ++counters_.dropped_overflow;
  }
  pending_.push_back(Pending{std::move(frame), now_ns});
}

std::vector<MatchedFrame> FramePoseMatcher::Poll(int64_t now_ns) {
  std::vector<MatchedFrame> out;
  std::deque<Pending> keep;
  for (Pending& p : pending_) {
    const scene::PoseLookup r = poses_.Lookup(p.frame.stamp_ns, options_.tolerance_ns);
    switch (r.status) {
      case scene::PoseLookupStatus::kOk:
        out.push_back(MatchedFrame{std::move(p.frame), *r.pose});
        ++counters_.matched;
        break;
      case scene::PoseLookupStatus::kTooOld: ++counters_.dropped_too_old; break;
      case scene::PoseLookupStatus::kGapTooBig: ++counters_.dropped_gap; break;
      case scene::PoseLookupStatus::kEmpty:
      case scene::PoseLookupStatus::kNotYet:
        // A newer pose can still bracket the stamp (poses may arrive late or out of order):
        // wait, but not longer than max_wait.
        if (now_ns - p.arrived_ns >= options_.max_wait_ns) {
          ++counters_.dropped_timeout;
        } else {
          keep.push_back(std::move(p));
        }
        break;
    }
  }
  pending_ = std::move(keep);
  return out;
}

}  // namespace p2i::nodes
