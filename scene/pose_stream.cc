/// @file pose_stream.cc
#include "scene/pose_stream.h"

#include <algorithm>
#include <stdexcept>

namespace p2i::scene {

const char* ToString(PoseLookupStatus status) {
  switch (status) {
    case PoseLookupStatus::kOk: return "ok";
    case PoseLookupStatus::kEmpty: return "empty";
    case PoseLookupStatus::kTooOld: return "too_old";
    case PoseLookupStatus::kNotYet: return "not_yet";
    case PoseLookupStatus::kGapTooBig: return "gap_too_big";
  }
  return "?";
}

std::string PoseLookup::Describe(int64_t stamp_ns) const {
  const auto ms = [](int64_t ns) { return std::to_string(static_cast<double>(ns) * 1e-6); };
  switch (status) {
    case PoseLookupStatus::kOk: return "pose found";
    case PoseLookupStatus::kEmpty: return "no pose received yet";
    case PoseLookupStatus::kTooOld:
      return "stamp is " + ms(before_ns - stamp_ns) + " ms older than the oldest pose kept";
    case PoseLookupStatus::kNotYet:
      return "stamp is " + ms(stamp_ns - before_ns) + " ms newer than the newest pose";
    case PoseLookupStatus::kGapTooBig:
      return "nearest poses are " + ms(stamp_ns - before_ns) + " ms before and " +
             ms(after_ns - stamp_ns) + " ms after the stamp (beyond the tolerance)";
  }
  return "?";
}

PoseStream::PoseStream(size_t capacity) : capacity_(capacity) {
  if (capacity < 2) throw std::invalid_argument("PoseStream: capacity must be >= 2");
}

PoseStream::AddResult PoseStream::Add(int64_t stamp_ns, const Pose& pose) {
  auto it = std::lower_bound(poses_.begin(), poses_.end(), stamp_ns,
                             [](const Entry& e, int64_t s) { return e.stamp_ns < s; });
  if (it != poses_.end() && it->stamp_ns == stamp_ns) {
    it->pose = pose;
    return AddResult::kDuplicate;
  }
  if (poses_.size() >= capacity_ && it == poses_.begin()) return AddResult::kTooOld;
  poses_.insert(it, Entry{stamp_ns, pose});
  while (poses_.size() > capacity_) poses_.pop_front();
  return AddResult::kAdded;
}

PoseLookup PoseStream::Lookup(int64_t stamp_ns, int64_t tolerance_ns) const {
  PoseLookup out;
  if (poses_.empty()) return out;  // kEmpty
  if (stamp_ns < poses_.front().stamp_ns) {
    out.status = PoseLookupStatus::kTooOld;
    out.before_ns = poses_.front().stamp_ns;
    return out;
  }
  if (stamp_ns > poses_.back().stamp_ns) {
    out.status = PoseLookupStatus::kNotYet;
    out.before_ns = poses_.back().stamp_ns;
    return out;
  }
  auto hi = std::lower_bound(poses_.begin(), poses_.end(), stamp_ns,
                             [](const Entry& e, int64_t s) { return e.stamp_ns < s; });
  if (hi->stamp_ns == stamp_ns) {
    out.status = PoseLookupStatus::kOk;
    out.pose = hi->pose;
    out.before_ns = out.after_ns = stamp_ns;
    return out;
  }
  auto lo = hi - 1;  // exists: stamp > front and hi is the first >= stamp
  out.before_ns = lo->stamp_ns;
  out.after_ns = hi->stamp_ns;
  if (stamp_ns - lo->stamp_ns > tolerance_ns || hi->stamp_ns - stamp_ns > tolerance_ns) {
    out.status = PoseLookupStatus::kGapTooBig;
    return out;
  }
  const double alpha = static_cast<double>(stamp_ns - lo->stamp_ns) /
                       static_cast<double>(hi->stamp_ns - lo->stamp_ns);
  out.status = PoseLookupStatus::kOk;
  out.pose = Pose::Interpolate(lo->pose, hi->pose, alpha);
  return out;
}

}  // namespace p2i::scene
