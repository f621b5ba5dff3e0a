/// @file slam_sink.cc
/// @brief SlamSink.
#include "nodes/slam_sink/slam_sink.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <utility>

#include "util/json_number.h"

namespace p2i::slam_sink {
namespace {

using util::NumberOrNull;

nlohmann::json ToJson(const ErrorSummary& s) {
  return {{"count", s.count},
          {"mean", NumberOrNull(s.mean)},
          {"median", NumberOrNull(s.median)},
          {"p90", NumberOrNull(s.p90)},
          {"max", NumberOrNull(s.max)}};
}

}  // namespace

SlamSink::SlamSink(SlamSinkOptions options, std::optional<scene::CameraInfo> camera)
    : options_((options.Validate(), std::move(options))), writer_(options_.writer) {
  if (camera) {
    WriteCamera(*camera);
    if (options_.check) checker_ = std::make_unique<OdometryChecker>(options_.checker, *camera);
  }
}

void SlamSink::WriteCamera(const scene::CameraInfo& camera) {
  // scene::ReadTumRgbd (and our dataset loader) take the calibration from this file.
  camera.ToYamlFile((std::filesystem::path(options_.writer.out_dir) / "camera_info.yaml").string());
  camera_written_ = true;
  camera_ = camera;
  camera_size_ = {camera.image_width, camera.image_height};
}

bool SlamSink::SetCamera(const scene::CameraInfo& camera) {
  if (!camera_written_) WriteCamera(camera);
  if (!options_.check || checker_) return false;
  checker_ = std::make_unique<OdometryChecker>(options_.checker, camera);
  return true;
}

SlamSink::Outcome SlamSink::Process(const SinkFrame& frame) {
  if (closed_) throw std::logic_error("SlamSink::Process after Close");
  if (camera_written_ && written_frames_ == 0 && !frame.rgb.empty() &&
      (frame.rgb.cols != camera_size_.first || frame.rgb.rows != camera_size_.second)) {
    // The first view fixes the sequence's image size: camera_info.yaml must describe it (p2i's
    // own reader refuses a sequence whose calibration has another size), so it is rewritten
    // for the views' size (same field of view) -- as the odometry check scales it too.
    WriteCamera(camera_.Scaled(frame.rgb.cols, frame.rgb.rows));
  }
  if (camera_written_ && (frame.rgb.cols != camera_size_.first || frame.rgb.rows != camera_size_.second)) {
    // A later view of another size: the sequence's camera_info.yaml would not describe it.
    throw std::invalid_argument(
        "view " + std::to_string(frame.rgb.cols) + "x" + std::to_string(frame.rgb.rows) +
        " does not match the sequence's camera_info " + std::to_string(camera_size_.first) + "x" +
        std::to_string(camera_size_.second) +
        " (set by the sequence's first view): one sequence holds views of one size");
  }
  ++written_frames_;
  Outcome outcome;
  ++received_;
  outcome.sequence = tracker_.Observe(frame.source, frame.seq, &outcome.gap, frame.publish_stamp_ns);
  if (outcome.sequence == SequenceTracker::Outcome::kDuplicate) {
    ++duplicates_;
    outcome.duplicate = true;
    return outcome;
  }
  if (!frame.synthetic && !options_.write_real) {
    ++real_skipped_;
    return outcome;
  }
  FrameRecord record;
  if (frame.synthetic && checker_) {
    outcome.check = checker_->Check(frame.rgb, frame.depth, frame.pose, frame.coverage);
    record.check = outcome.check.StatusName();
    record.translation_error_m = outcome.check.translation_error_m;
    record.rotation_error_deg = outcome.check.rotation_error_deg;
    if (outcome.check.status == CheckResult::Status::kFail) {
      if (options_.policy == "drop") {
        ++dropped_;
        return outcome;
      }
      ++flagged_;
    }
  } else if (!frame.synthetic) {
    record.check = "real";
  }
  try {
    outcome.files = writer_.Write(frame, record);
  } catch (...) {
    ++write_errors_;
    throw;
  }
  outcome.written = true;
  if (frame.synthetic) {
    ++synthetic_written_;
  } else {
    ++real_written_;
  }
  return outcome;
}

nlohmann::json SlamSink::Summary() const {
  nlohmann::json j;
  j["out_dir"] = options_.writer.out_dir;
  j["frames_received"] = received_;
  j["frames_written"] = writer_.frames_written();
  j["synthetic_written"] = synthetic_written_;
  j["real_written"] = real_written_;
  j["real_skipped"] = real_skipped_;
  j["duplicates"] = duplicates_;
  j["write_errors"] = write_errors_;
  j["depth_pixels_out_of_range"] = writer_.depth_pixels_out_of_range();
  nlohmann::json check;
  check["enabled"] = checker_ != nullptr;
  check["policy"] = options_.policy;
  check["flagged"] = flagged_;
  check["dropped"] = dropped_;
  if (checker_) {
    const CheckerStats& s = checker_->stats();
    check["method"] = checker_->options().method;
    check["checked"] = s.checked;
    check["passed"] = s.passed;
    check["failed"] = s.failed;
    check["unchecked"] = s.unchecked;
    check["pass_rate"] = NumberOrNull(s.checked ? s.pass_rate() : NAN);
    check["failed_coverage"] = s.failed_coverage;
    check["failed_depth"] = s.failed_depth;
    check["failed_odometry"] = s.failed_odometry;
    check["failed_motion"] = s.failed_motion;
    check["translation_error_m"] = ToJson(s.translation_error_m);
    check["rotation_error_deg"] = ToJson(s.rotation_error_deg);
    check["max_translation_error_m"] = checker_->options().max_translation_error_m;
    check["max_rotation_error_deg"] = checker_->options().max_rotation_error_deg;
    check["min_coverage"] = checker_->options().min_coverage;
  }
  j["check"] = check;
  nlohmann::json sequences = nlohmann::json::object();
  for (const auto& [source, a] : tracker_.accounts()) {
    nlohmann::json ranges = nlohmann::json::array();
    for (const auto& [lo, hi] : a.MissingRanges()) ranges.push_back({lo, hi});
    sequences[source] = {{"first_seq", a.first_seq},
                         {"last_seq", a.last_seq},
                         {"received", a.received},
                         {"missing_count", a.missing.size()},
                         {"missing", ranges},
                         {"duplicates", a.duplicates},
                         {"late", a.late},
                         {"before_first", a.before_first}};
  }
  j["sequences"] = sequences;
  j["total_missing"] = tracker_.TotalMissing();
  return j;
}

std::string SlamSink::SummaryLine() const {
  char buf[512];
  const CheckerStats* s = checker_ ? &checker_->stats() : nullptr;
  std::snprintf(buf, sizeof(buf),
                "wrote %zu frames (%llu synthetic, %llu real) to %s; check %s: pass rate %.3f "
                "(%zu/%zu), odometry error median %.4f m / %.3f deg, p90 %.4f m / %.3f deg; "
                "flagged %llu, dropped %llu; missing seq %llu, duplicates %llu",
                writer_.frames_written(), static_cast<unsigned long long>(synthetic_written_),
                static_cast<unsigned long long>(real_written_), options_.writer.out_dir.c_str(),
                s ? "on" : "off", s ? s->pass_rate() : 0.0, s ? s->passed : 0,
                s ? s->checked : 0, s ? s->translation_error_m.median : NAN,
                s ? s->rotation_error_deg.median : NAN, s ? s->translation_error_m.p90 : NAN,
                s ? s->rotation_error_deg.p90 : NAN, static_cast<unsigned long long>(flagged_),
                static_cast<unsigned long long>(dropped_),
                static_cast<unsigned long long>(tracker_.TotalMissing()),
                static_cast<unsigned long long>(duplicates_));
  return buf;
}

void SlamSink::WriteSummary() const {
  namespace fs = std::filesystem;
  const fs::path path = fs::path(options_.writer.out_dir) / "summary.json";
  const fs::path temp = fs::path(options_.writer.out_dir) / ".summary.json.tmp";
  {
    std::ofstream out(temp);
    out << Summary().dump(2) << "\n";
    if (!out) {
      throw std::runtime_error("SlamSink: cannot write '" + temp.string() + "' (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(temp, path, ec);
  if (ec) {
    throw std::runtime_error("SlamSink: cannot rename '" + temp.string() + "' to '" +
                             path.string() + "': " + ec.message());
  }
}

void SlamSink::Close() {
  if (closed_) return;
  closed_ = true;
  writer_.Close();
  WriteSummary();
}

}  // namespace p2i::slam_sink
