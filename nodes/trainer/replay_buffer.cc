/// @file replay_buffer.cc
/// @brief ReplayBuffer: recent window + reservoir, persisted as p2i capture generations.
#include "nodes/trainer/replay_buffer.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "scene/image_ops.h"

namespace p2i::trainer {

namespace fs = std::filesystem;

namespace {
constexpr char kStateFile[] = "buffer_state.yaml";
}  // namespace

void ReplayBuffer::Options::Validate() const {
  if (!(max_mb > 0)) throw std::invalid_argument("ReplayBuffer: max_mb must be > 0");
  if (!(recent_fraction > 0 && recent_fraction <= 1))
    throw std::invalid_argument("ReplayBuffer: recent_fraction must be in (0, 1]");
  if (width < 1 || height < 1)
    throw std::invalid_argument("ReplayBuffer: width and height must be positive");
}

ReplayBuffer::ReplayBuffer(const Options& options) : options_(options), rng_(options.seed) {
  options_.Validate();
  const double bytes = options_.max_mb * 1024.0 * 1024.0;
  capacity_ = std::max<size_t>(
      2, static_cast<size_t>(bytes / BytesPerFrame(options_.width, options_.height)));
  recent_capacity_ = std::min(
      capacity_, std::max<size_t>(1, static_cast<size_t>(
                                         std::ceil(capacity_ * options_.recent_fraction))));
  if (!options_.dir.empty()) {
    fs::create_directories(options_.dir);
    Reload();
  }
}

ReplayBuffer::~ReplayBuffer() = default;

std::string ReplayBuffer::GenFolder(int generation) const {
  char name[32];
  std::snprintf(name, sizeof(name), "gen_%06d", generation);
  return (fs::path(options_.dir) / name).string();
}

bool ReplayBuffer::Add(const scene::RgbdSample& sample, const scene::CameraInfo& camera,
                       bool has_pose) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!has_pose) {
    ++dropped_no_pose_;
    return false;
  }
  if (!have_camera_) {
    camera_ = scene::CenterCropResizeCamera(camera, options_.width, options_.height);
    have_camera_ = true;
  }
  Entry entry;
  entry.sample = scene::CenterCropResizeSample(sample, options_.width, options_.height);
  if (!options_.dir.empty()) Persist(entry.sample, &entry);
  Insert(std::move(entry));
  ++accepted_;
  if (!options_.dir.empty()) {
    if (writer_->size() >= 2 * capacity_) Compact();
    else WriteState();
  }
  return true;
}

void ReplayBuffer::Insert(Entry entry) {
  recent_.push_back(std::move(entry));
  if (recent_.size() <= recent_capacity_) return;
  Entry old = std::move(recent_.front());
  recent_.pop_front();
  const size_t k = capacity_ - recent_capacity_;
  ++left_window_;
  if (k == 0) return;
  if (reservoir_.size() < k) {
    reservoir_.push_back(std::move(old));
    return;
  }
  std::uniform_int_distribution<uint64_t> pick(0, left_window_ - 1);
  const uint64_t j = pick(rng_);
  if (j < k) reservoir_[j] = std::move(old);
}

void ReplayBuffer::Persist(const scene::RgbdSample& s, Entry* entry) {
  if (!writer_) {
    scene::CaptureWriter::Options o;
    o.overwrite = true;
    writer_ = std::make_unique<scene::CaptureWriter>(GenFolder(generation_), camera_, o);
  }
  entry->disk_index = writer_->size();
  writer_->Append(s);
}

void ReplayBuffer::WriteState() {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "generation" << YAML::Value << generation_;
  out << YAML::Key << "disk_frames" << YAML::Value << writer_->size();
  out << YAML::Key << "left_window" << YAML::Value << left_window_;
  out << YAML::Key << "reservoir" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& e : reservoir_) out << e.disk_index;
  out << YAML::EndSeq;
  out << YAML::Key << "recent" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& e : recent_) out << e.disk_index;
  out << YAML::EndSeq;
  out << YAML::EndMap;
  scene::WriteFileAtomic((fs::path(options_.dir) / kStateFile).string(),
                         std::string(out.c_str()) + "\n");
}

void ReplayBuffer::Compact() {
  // Next generation: the buffer's frames only; the state switch is the commit point.
  const int next = generation_ + 1;
  scene::CaptureWriter::Options o;
  o.overwrite = true;
  auto writer = std::make_unique<scene::CaptureWriter>(GenFolder(next), camera_, o);
  for (auto& e : reservoir_) {
    e.disk_index = writer->size();
    writer->Append(e.sample);
  }
  for (auto& e : recent_) {
    e.disk_index = writer->size();
    writer->Append(e.sample);
  }
  const int old = generation_;
  generation_ = next;
  writer_ = std::move(writer);
  WriteState();
  std::error_code ec;
  fs::remove_all(GenFolder(old), ec);
}

void ReplayBuffer::Reload() {
  const fs::path state_path = fs::path(options_.dir) / kStateFile;
  int generation = -1;
  size_t disk_frames = 0;
  std::vector<size_t> reservoir, recent;
  if (fs::exists(state_path)) {
    try {
      const YAML::Node s = YAML::LoadFile(state_path.string());
      generation = s["generation"].as<int>();
      disk_frames = s["disk_frames"].as<size_t>();
      left_window_ = s["left_window"].as<uint64_t>();
      reservoir = s["reservoir"].as<std::vector<size_t>>();
      recent = s["recent"].as<std::vector<size_t>>();
    } catch (const std::exception& e) {
      throw std::runtime_error("ReplayBuffer: cannot read " + state_path.string() + ": " +
                               e.what() + " (delete the folder " + options_.dir +
                               " to start with an empty buffer)");
    }
  } else {
    // No state yet: the newest generation folder (if any) is replayed whole.
    for (const auto& entry : fs::directory_iterator(options_.dir)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_directory() && name.rfind("gen_", 0) == 0)
        generation = std::max(generation, std::atoi(name.c_str() + 4));
    }
  }
  // Stale generations (a crash during compaction) go away.
  for (const auto& entry : fs::directory_iterator(options_.dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && name.rfind("gen_", 0) == 0 &&
        std::atoi(name.c_str() + 4) != generation) {
      std::error_code ec;
      fs::remove_all(entry.path(), ec);
    }
  }
  if (generation < 0 || !scene::IsCaptureFolder(GenFolder(generation))) {
    generation_ = std::max(0, generation + 1);
    return;
  }
  generation_ = generation;
  const scene::DatasetIndex index = scene::ReadCapture(GenFolder(generation));
  camera_ = index.camera();
  have_camera_ = true;
  const auto load = [&](size_t i) {
    Entry e;
    e.sample = index.Load(i);
    return e;
  };
  for (size_t i : reservoir)
    if (i < index.size()) reservoir_.push_back(load(i));
  for (size_t i : recent)
    if (i < index.size()) recent_.push_back(load(i));
  // Frames written after the last state (state missing, or a crash before its update).
  for (size_t i = std::min(disk_frames, index.size()); i < index.size(); ++i) Insert(load(i));
  reloaded_ = reservoir_.size() + recent_.size();
  // The capture writer cannot append to an existing folder: continue in a new generation.
  Compact();
}

scene::RgbdDataset ReplayBuffer::Snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  scene::RgbdDataset d;
  d.camera = camera_;
  d.frames.reserve(reservoir_.size() + recent_.size());
  for (const auto& e : reservoir_) d.frames.push_back(e.sample);
  for (const auto& e : recent_) d.frames.push_back(e.sample);
  return d;
}

size_t ReplayBuffer::Size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reservoir_.size() + recent_.size();
}

uint64_t ReplayBuffer::Accepted() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return accepted_;
}

uint64_t ReplayBuffer::DroppedNoPose() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_no_pose_;
}

}  // namespace p2i::trainer
