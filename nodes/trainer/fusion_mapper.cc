/// @file fusion_mapper.cc
/// @brief FusionMapper: the mapping thread (queue -> TSDF + keyframes -> versions).
#include "nodes/trainer/fusion_mapper.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "fusion/fusion_version_io.h"
#include "scene/capture.h"

namespace p2i::trainer {

namespace fs = std::filesystem;

void FusionMapperOptions::Validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("fusion mapper: " + what);
  };
  scene.Validate();
  if (work_dir.empty()) fail("work_dir is empty");
  if (publish_every_frames < 1)
    fail("publish_every_frames must be >= 1, got " + std::to_string(publish_every_frames));
  if (keep_versions < 1) fail("keep_versions must be >= 1, got " + std::to_string(keep_versions));
  if (!(keep_seconds >= 0.0) || !std::isfinite(keep_seconds))
    fail("keep_seconds must be finite and >= 0, got " + std::to_string(keep_seconds));
  if (queue_frames < 1) fail("queue_frames must be >= 1, got " + std::to_string(queue_frames));
  if (!refine_net.empty() && !fs::is_regular_file(refine_net))
    fail("refine_net: no file '" + refine_net + "' (a `p2i refine train-sim` output such as "
         "models/refine_sim.pt, or '' for none)");
  if (refine_finetune_steps < 0)
    fail("refine_finetune_steps must be >= 0, got " + std::to_string(refine_finetune_steps));
  if (refine_finetune_steps > 0) TunerOptions().Validate();
}

RefineTunerOptions FusionMapperOptions::TunerOptions() const {
  RefineTunerOptions t;
  t.net = refine_net;
  t.scene = scene;
  t.steps_per_round = refine_finetune_steps;
  t.window_keyframes = refine_window_keyframes;
  t.view_width = refine_view_width;
  t.out_dir = (fs::path(work_dir) / "refine").string();
  return t;
}

FusionMapper::FusionMapper(FusionMapperOptions options, VersionCallback on_version)
    : options_(std::move(options)), on_version_(std::move(on_version)) {
  options_.Validate();
  versions_dir_ = (fs::absolute(options_.work_dir) / "versions").string();
  fs::create_directories(versions_dir_);
  // A killed writer's temps; old versions only once keep_seconds old (a reader may be loading one).
  model::PruneFusionVersions(versions_dir_, options_.keep_versions, options_.keep_seconds);
  const std::vector<uint64_t> existing = model::ListFusionVersions(versions_dir_);
  next_version_ = existing.empty() ? 1 : existing.back() + 1;
  char name[32];
  std::snprintf(name, sizeof(name), "keyframes_s%06llu",
                static_cast<unsigned long long>(next_version_));
  keyframes_dir_ = (fs::absolute(options_.work_dir) / name).string();
  if (options_.refine_finetune_steps > 0)
    tuner_ = std::make_unique<RefineTuner>(options_.TunerOptions());
  writer_ = std::thread([this] { WriteVersions(); });
  thread_ = std::thread([this] { Run(); });
}

FusionMapper::~FusionMapper() { Stop(); }

void FusionMapper::Submit(scene::RgbdSample frame, const scene::CameraInfo& camera, bool wait) {
  std::unique_lock<std::mutex> lock(mutex_);
  ++stats_.received;
  if (stopping_) return;
  if (wait) {
    cv_.wait(lock, [this] {
      return stopping_ || queue_.size() < static_cast<size_t>(options_.queue_frames);
    });
  } else if (queue_.size() >= static_cast<size_t>(options_.queue_frames)) {
    queue_.pop_front();
    ++stats_.dropped;
  }
  queue_.push_back({std::move(frame), camera, wait});
  cv_.notify_all();
}

void FusionMapper::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();  // its last version is handed to the writer
  {
    std::lock_guard<std::mutex> lock(mutex_);
    writer_stop_ = true;
  }
  write_cv_.notify_all();
  if (writer_.joinable()) writer_.join();  // writes what is pending first
  if (tuner_) tuner_->Stop();
}

FusionMapper::Stats FusionMapper::GetStats() const {
  Stats st;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    st = stats_;
  }
  if (tuner_) {
    const RefineTuner::Stats t = tuner_->GetStats();
    st.refine_rounds = t.rounds;
    st.refine_steps = t.total_steps;
    st.refine_loss = t.last_loss;
    st.refine_error = t.last_error;
  }
  return st;
}

void FusionMapper::Run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      // With online fine-tuning, wake now and then: a net finished after the last version goes
      // out in a version of its own when no frame comes (a robot standing still, offline data).
      const auto ready = [this] { return stopping_ || !queue_.empty(); };
      if (tuner_) {
        cv_.wait_for(lock, std::chrono::milliseconds(200), ready);
      } else {
        cv_.wait(lock, ready);
      }
      if (queue_.empty()) {
        if (stopping_) break;  // everything queued integrated
        lock.unlock();
        if (scene_ && (tuner_->LatestNet().steps > published_refine_steps_ || RetryDue())) Publish(false);
        continue;
      }
      job = std::move(queue_.front());
      queue_.pop_front();
    }
    cv_.notify_all();  // a waiting Submit may queue now
    Integrate(job);
    if (unpublished_ >= static_cast<uint64_t>(options_.publish_every_frames) || RetryDue())
      Publish(job.wait);
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    write_cv_.wait(lock, [this] { return !writing_; });  // a failed write is tried once more below
  }
  if (unpublished_ > 0 || RetryDue()) Publish(true);
}

bool FusionMapper::RetryDue() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return retry_ && !writing_;
}

void FusionMapper::Integrate(const Job& job) {
  const auto t0 = std::chrono::steady_clock::now();
  bool keyframe = false;
  try {
    if (!scene_) {
      scene_ = std::make_unique<fusion::FusionScene>(job.camera, options_.scene);
      // A folder of this name holds no committed version's keyframes (its number would be
      // lower than next_version_ otherwise): what a killed session left is started over.
      scene::CaptureWriter::Options capture;
      capture.overwrite = true;
      keyframes_ = std::make_unique<scene::CaptureWriter>(keyframes_dir_, job.camera, capture);
    } else if (!job.camera.equals(scene_->frame_camera(), 1e-6)) {
      throw std::invalid_argument("its camera differs from the first frame's (" +
                                  std::to_string(scene_->frame_camera().image_width) + "x" +
                                  std::to_string(scene_->frame_camera().image_height) +
                                  "): one mapper maps one camera");
    }
    keyframe = scene_->AddFrame(job.frame);
    if (keyframe) keyframes_->Append(job.frame);
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.rejected;
    stats_.last_error = "frame '" + job.frame.id + "': " + e.what();
    return;
  }
  ++unpublished_;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.integrated;
  if (keyframe) ++stats_.keyframes;
  stats_.last_integrate_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void FusionMapper::Publish(bool wait) {
  if (!scene_) return;  // every frame so far was refused: nothing to write
  fusion::FusionVersionInfo info;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (writing_) {
      if (!wait) return;  // taken at the first frame after that write
      write_cv_.wait(lock, [this] { return !writing_; });
    }
    unpublished_ += retry_frames_;  // a failed write's frames go out with this version
    retry_frames_ = 0;
    retry_ = false;
    info.version = next_version_;
    info.previous_dir = last_version_dir_;
    info.frames_integrated = stats_.integrated;
  }
  info.keyframes_dir = keyframes_dir_;
  info.keyframe_count = keyframes_->size();
  info.refine_source = options_.refine_net;
  if (tuner_) {
    const RefineTuner::Net net = tuner_->LatestNet();
    if (!net.path.empty()) {
      info.refine_source = net.path;
      info.refine_steps = net.steps;
    }
  }
  std::unique_ptr<fusion::SceneVersionSnapshot> snapshot;
  try {
    snapshot = std::make_unique<fusion::SceneVersionSnapshot>(
        fusion::SnapshotSceneVersion(versions_dir_, *scene_, info));
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.last_error = std::string("version ") + std::to_string(info.version) + ": " + e.what();
    return;  // unpublished_ kept: tried again at the next frame
  }
  const uint64_t frames = unpublished_;
  unpublished_ = 0;
  published_refine_steps_ = info.refine_steps;
  // The next round tunes on the keyframes of this version; only when new frames came: a version
  // for a new net alone would otherwise start a round on the same keyframes, for ever.
  if (tuner_ && frames > 0) tuner_->Offer(scene_->keyframes(), scene_->frame_camera());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = std::move(snapshot);
    pending_frames_ = frames;
    writing_ = true;
  }
  write_cv_.notify_all();
}

void FusionMapper::WriteVersions() {
  for (;;) {
    std::unique_ptr<fusion::SceneVersionSnapshot> job;
    uint64_t frames = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      write_cv_.wait(lock, [this] { return writer_stop_ || pending_ != nullptr; });
      if (!pending_) break;  // stopping, nothing left to write
      job = std::move(pending_);
      frames = pending_frames_;
    }
    std::string dir, error;
    try {
      dir = fusion::WriteSceneVersion(*job);
    } catch (const std::exception& e) {
      error = std::string("version ") + std::to_string(job->info.version) + ": " + e.what();
    }
    if (error.empty()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        next_version_ = job->info.version + 1;
        last_version_dir_ = dir;
        ++stats_.versions;
        stats_.last_version = job->info.version;
      }
      job.reset();  // the copies' memory goes before the next snapshot's
      try {
        Prune();
        if (on_version_) on_version_(model::ReadFusionVersion(dir), dir);
      } catch (const std::exception& e) {
        // The version is committed; what failed after it must not end the writer thread.
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.last_error = "version " + dir + " written, then: " + e.what();
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error.empty()) {
        stats_.last_error = error;
        retry_frames_ += frames;
        retry_ = true;
      }
      writing_ = false;
    }
    write_cv_.notify_all();
    cv_.notify_all();  // a mapping thread idle with a failed write retries at its next wake
  }
}

/// Old versions beyond keep_versions, and keyframe folders of earlier sessions that no kept
/// version references.
void FusionMapper::Prune() {
  model::PruneFusionVersions(versions_dir_, options_.keep_versions, options_.keep_seconds);
  std::set<std::string> used{keyframes_dir_};
  for (const uint64_t v : model::ListFusionVersions(versions_dir_)) {
    try {
      used.insert(model::ReadFusionVersion(model::FusionVersionDir(versions_dir_, v)).keyframes_dir);
    } catch (const std::exception&) {
      // an unreadable version keeps nothing alive; the synthesizer refuses it with the reason
    }
  }
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(options_.work_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("keyframes_s", 0) == 0 && !used.count(fs::absolute(e.path()).string()))
      fs::remove_all(e.path(), ec);
  }
}

}  // namespace p2i::trainer
