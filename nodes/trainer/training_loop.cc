/// @file training_loop.cc
/// @brief TrainingLoop: rounds of model::Trainer with resume on a buffer snapshot.
#include "nodes/trainer/training_loop.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "scene/capture.h"
#include "scene/trajectory_io.h"

namespace p2i::trainer {

namespace fs = std::filesystem;

namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

uint64_t HighestVersion(const std::string& work_dir) {
  uint64_t best = 0;
  const fs::path dir = fs::path(work_dir) / "versions";
  if (!fs::exists(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("model_v", 0) == 0 && e.path().extension() == ".pt")
      best = std::max<uint64_t>(best, std::strtoull(n.c_str() + 7, nullptr, 10));
  }
  return best;
}

}  // namespace

void TrainingLoop::Options::Validate() const {
  config.Validate();
  if (work_dir.empty()) throw std::invalid_argument("TrainingLoop: work_dir is empty");
  if (steps_per_round < 1) throw std::invalid_argument("TrainingLoop: steps_per_round must be >= 1");
  if (enet_steps_per_round < -1)
    throw std::invalid_argument("TrainingLoop: enet_steps_per_round must be >= -1 (-1 = steps_per_round)");
  if (threads < 1) throw std::invalid_argument("TrainingLoop: threads must be >= 1");
  if (min_frames < 2) throw std::invalid_argument("TrainingLoop: min_frames must be >= 2");
  if (val_every_nth < 2) throw std::invalid_argument("TrainingLoop: val_every_nth must be >= 2");
  if (!warm_start.empty() && !fs::exists(warm_start))
    throw std::invalid_argument("TrainingLoop: warm-start checkpoint " + warm_start +
                                " does not exist");
  distributed.Validate();
}

std::string TrainingLoop::PosesPath(const std::string& version_path) {
  const std::string ext = ".pt";
  const bool has_ext = version_path.size() >= ext.size() &&
                       version_path.compare(version_path.size() - ext.size(), ext.size(), ext) == 0;
  return (has_ext ? version_path.substr(0, version_path.size() - ext.size()) : version_path) +
         ".poses.txt";
}

std::string TrainingLoop::VersionPath(const std::string& work_dir, uint64_t version) {
  char name[48];
  std::snprintf(name, sizeof(name), "model_v%06llu.pt", static_cast<unsigned long long>(version));
  return (fs::absolute(fs::path(work_dir) / "versions") / name).string();
}

TrainingLoop::TrainingLoop(const Options& options, ReplayBuffer* buffer,
                           VersionCallback on_version, StatusCallback on_status)
    : options_(options),
      buffer_(buffer),
      on_version_(std::move(on_version)),
      on_status_(std::move(on_status)) {
  options_.Validate();
  status_.set_phase("idle");
  status_.set_world_size(static_cast<uint32_t>(options_.distributed.world_size));
  status_.set_rank(static_cast<uint32_t>(options_.distributed.rank));
}

TrainingLoop::~TrainingLoop() {
  stop_ = true;
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void TrainingLoop::Start() {
  fs::create_directories(fs::path(options_.work_dir) / "versions");
  version_ = HighestVersion(options_.work_dir);
  const std::string ckpt = model::Trainer::CheckpointPath(options_.work_dir);
  if (!options_.warm_start.empty() && !fs::exists(ckpt))
    scene::WriteFileAtomic(ckpt, ReadFile(options_.warm_start));
  thread_ = std::thread([this] { Main(); });
}

void TrainingLoop::Join() {
  stop_ = true;
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool TrainingLoop::Stop(std::chrono::milliseconds wait) {
  stop_ = true;
  cv_.notify_all();
  if (!thread_.joinable()) return true;
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_for(lock, wait, [this] { return finished_.load(); });
  const bool done = finished_;
  lock.unlock();
  if (done) thread_.join();
  return done;
}

std::string TrainingLoop::Error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

std::string TrainingLoop::StopReason() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stop_reason_;
}

msgs::pb::TrainerStatus TrainingLoop::LastStatus() const {
  std::lock_guard<std::mutex> lock(mutex_);
  msgs::pb::TrainerStatus s = status_;
  s.set_buffer_size(buffer_->Size());
  return s;
}

void TrainingLoop::SetPhase(const std::string& phase) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (status_.phase() == phase) return;
    status_.set_phase(phase);
  }
  EmitStatus();
}

void TrainingLoop::EmitStatus() {
  if (on_status_) on_status_(LastStatus());
}

void TrainingLoop::ReadLosses() {
  // The trainer logs one JSON line per step; the last phase-1 step line has the losses.
  // (model::Trainer's log name: ranks other than 0 write train_log.rank<R>.jsonl.)
  const int rank = options_.distributed.Enabled() ? options_.distributed.rank : 0;
  std::ifstream in(options_.work_dir + (rank > 0 ? "/train_log.rank" + std::to_string(rank) +
                                                       ".jsonl"
                                                 : "/train_log.jsonl"),
                   std::ios::binary);
  if (!in) return;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff from = std::max<std::streamoff>(0, size - 16384);
  in.seekg(from);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find("\"loss") != std::string::npos) last = line;
  if (last.empty()) return;
  try {
    const auto j = nlohmann::json::parse(last);
    std::lock_guard<std::mutex> lock(mutex_);
    status_.clear_losses();
    for (auto it = j.begin(); it != j.end(); ++it)
      if (it.value().is_number() && it.key() != "phase" && it.key() != "step")
        (*status_.mutable_losses())[it.key()] = it.value().get<double>();
  } catch (const std::exception&) {
    // a partial first line after seeking: no losses this time
  }
}

void TrainingLoop::Main() {
  try {
    RunRounds();
    SetPhase(stop_ || !StopReason().empty() ? "stopped" : "done");
  } catch (const std::exception& e) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = e.what();
      status_.set_error(error_);
    }
    SetPhase("error");
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
  }
  cv_.notify_all();
}

void TrainingLoop::WriteFirstCheckpoint(const scene::RgbdDataset& train,
                                        const scene::RgbdDataset& val) {
  // A 0-step run of every rank together (model::Trainer's data-parallel fresh start): rank 0
  // writes checkpoint.pt with the weights at step 0 and the pose normaliser of every rank's
  // frames (their bounds all-reduced), which every rank then resumes from.
  model::TrainerOptions t;
  t.out_dir = options_.work_dir;
  t.phase = 1;
  t.steps = 0;
  t.threads = options_.threads;
  t.progress = false;
  t.max_val_frames = options_.max_val_frames;
  t.distributed = options_.distributed;  // with every rank: the normaliser of all ranks' frames
  model::Trainer(options_.config, t).Run(train, val);
}

void TrainingLoop::RunRounds() {
  RankSync ranks(options_.distributed);
  Progress progress;
  // Else a 0-step run reads it from the checkpoint; data-parallel ranks always start so, from
  // rank 0's checkpoint (StartFromRankZero), whatever their own work dir holds.
  progress.know_step =
      !ranks.Enabled() && !fs::exists(model::Trainer::CheckpointPath(options_.work_dir));
  scene::RgbdDataset all;
  while (WaitForRound(ranks, progress, &all)) {
    const RoundData data = HoldOut(all);
    SetPhase("training");
    StartFromRankZero(ranks, data);
    const auto t0 = std::chrono::steady_clock::now();
    const model::TrainReport report = TrainRound(progress, data);
    if (report.stopped) {
      // A partial round: its steps are in checkpoint.pt (the next start resumes from there),
      // but it is not published as a version. Every rank stopped at this step together.
      {
        std::lock_guard<std::mutex> lock(mutex_);
        status_.set_step(static_cast<uint64_t>(report.phase1_steps));
      }
      if (!stop_)
        StoppedBy("another rank was stopped during a round; every rank stopped at step " +
                  std::to_string(report.phase1_steps) + " (rank 0 saved checkpoint.pt there)");
      return;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!progress.know_step) {
      // Resumed (restart / warm start): learn the checkpoint's step, nothing trained yet.
      progress.step = report.phase1_steps;
      progress.step2 = report.phase2_steps;
      progress.know_step = true;
      continue;
    }
    RecordRound(report, seconds, &progress);
    if (ranks.IsWriter()) PublishVersion(report, data, progress.step);
    EmitStatus();  // rank 0 publishes the version the ranks trained together; the others none
  }
}

bool TrainingLoop::WaitForRound(RankSync& ranks, const Progress& progress,
                                scene::RgbdDataset* all) {
  // Every 100 ms until a round can start, in step with the other ranks (RankSync::Poll): a
  // rank that stops or has run its rounds says so in its last poll, and the others leave at
  // that same poll.
  for (;;) {
    const bool stopping = stop_.load();
    const bool finished = options_.max_rounds >= 0 && progress.rounds >= options_.max_rounds;
    *all = buffer_->Snapshot();
    const size_t have = all->frames.size();
    RoundPoll poll;
    try {
      poll = ranks.Poll(have >= options_.min_frames ? have : 0, stopping, finished);
    } catch (const std::runtime_error&) {
      if (stopping || finished) return false;  // leaving anyway; the others are gone
      throw;
    }
    if (stopping || finished) return false;
    const auto event = [&](int rank, const char* what) {
      StoppedBy("rank " + std::to_string(rank) + " " + what + " between rounds, so every rank " +
                "stopped there (step " + std::to_string(progress.step) + ")");
    };
    if (poll.stopped_rank >= 0) {
      event(poll.stopped_rank, "was stopped (its node shut down)");
      return false;
    }
    if (poll.finished_rank >= 0) {
      event(poll.finished_rank, "ran its max_rounds");
      return false;
    }
    if (poll.frames > 0) {
      // Each rank trains on the first n frames of its shard, n the smallest shard's size, so
      // every shard weighs the same.
      all->frames.erase(all->frames.begin() + std::min(all->frames.size(), poll.frames),
                        all->frames.end());
      return true;
    }
    SetPhase("waiting");
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stop_.load(); });
  }
}

void TrainingLoop::StoppedBy(const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  stop_reason_ = "data-parallel training: " + reason +
                 ". Rank 0's checkpoint.pt and versions are intact: start every rank again to "
                 "continue (each resumes from rank 0's checkpoint).";
  status_.set_error(stop_reason_);  // phase "stopped": what stopped it
}

TrainingLoop::RoundData TrainingLoop::HoldOut(const scene::RgbdDataset& all) const {
  RoundData data;
  data.train.camera = data.val.camera = all.camera;
  const size_t n = all.frames.size();
  const size_t every = static_cast<size_t>(options_.val_every_nth);
  const bool hold_out = n >= 2 * every;
  for (size_t i = 0; i < n; ++i) {
    if (hold_out && i % every == every / 2)
      data.val.frames.push_back(all.frames[i]);
    else
      data.train.frames.push_back(all.frames[i]);
  }
  return data;
}

void TrainingLoop::StartFromRankZero(RankSync& ranks, const RoundData& data) {
  // Every rank resumes from rank 0's checkpoint.pt. A fresh rank 0 (none yet): all ranks
  // first run a 0-step round together (WriteFirstCheckpoint), then share what rank 0 wrote.
  if (!ranks.Enabled()) return;
  const std::string ckpt = model::Trainer::CheckpointPath(options_.work_dir);
  if (ranks.ShareCheckpoint(ckpt)) return;
  WriteFirstCheckpoint(data.train, data.val);
  if (!ranks.ShareCheckpoint(ckpt))
    throw std::runtime_error("data-parallel training: rank 0 wrote no first checkpoint " + ckpt);
}

model::TrainReport TrainingLoop::TrainRound(const Progress& progress, const RoundData& data) {
  const std::string ckpt = model::Trainer::CheckpointPath(options_.work_dir);
  const bool enet = options_.config.enet && !options_.config.IsBaseline() &&
                    options_.enet_steps_per_round != 0;
  const int enet_steps =
      options_.enet_steps_per_round < 0 ? options_.steps_per_round : options_.enet_steps_per_round;
  model::TrainerOptions t;
  t.out_dir = options_.work_dir;
  t.phase = enet ? 0 : 1;
  t.steps = progress.know_step ? progress.step + options_.steps_per_round : 0;
  t.steps_phase2 = progress.know_step ? progress.step2 + enet_steps : 0;
  t.threads = options_.threads;
  t.resume = fs::exists(ckpt);
  t.progress = false;
  t.max_val_frames = options_.max_val_frames;
  // Polled between steps: on Stop() the trainer saves checkpoint.pt at the current step
  // (atomically) and returns, so shutdown never abandons a round.
  t.should_stop = [this] { return stop_.load(); };
  t.distributed = options_.distributed;  // every step's gradients averaged over the ranks
  model::Trainer trainer(options_.config, t);
  return trainer.Run(data.train, data.val);
}

void TrainingLoop::RecordRound(const model::TrainReport& report, double seconds,
                               Progress* progress) {
  const int done = report.phase1_steps - progress->step;
  progress->step = report.phase1_steps;
  progress->step2 = report.phase2_steps;
  ++progress->rounds;
  pose_dependence_ =
      std::isfinite(report.val_pose_dependence) ? report.val_pose_dependence : -1.0;
  ReadLosses();
  std::lock_guard<std::mutex> lock(mutex_);
  status_.set_step(static_cast<uint64_t>(progress->step));
  status_.set_steps_per_s(seconds > 0 ? done / seconds : 0.0);
}

void TrainingLoop::PublishVersion(const model::TrainReport& report, const RoundData& data,
                                  int step) {
  // A versioned copy, written atomically, that this loop never rewrites.
  const uint64_t version = version_ + 1;
  const std::string path = VersionPath(options_.work_dir, version);
  // The poses this model was trained on (the synthesizer's coverage score), then the model.
  const std::string poses_path = PosesPath(path);
  std::vector<scene::StampedPose> poses;
  poses.reserve(data.train.frames.size());
  for (const auto& f : data.train.frames) poses.push_back({f.stamp, f.pose});
  scene::WriteTumTrajectory(poses_path, poses,
                            "training poses of model version " + std::to_string(version));
  scene::WriteFileAtomic(path, ReadFile(report.checkpoint_path));
  version_ = version;
  msgs::pb::ModelVersion mv;
  mv.set_version(version);
  mv.set_checkpoint_path(path);
  mv.set_poses_path(poses_path);
  mv.set_step(static_cast<uint64_t>(step));
  mv.set_method("p2i_net");
  mv.set_val_psnr(report.val_psnr);
  mv.set_width(static_cast<uint32_t>(options_.config.resolution));
  mv.set_height(static_cast<uint32_t>(options_.config.resolution));
  if (on_version_) on_version_(mv);
}

}  // namespace p2i::trainer
