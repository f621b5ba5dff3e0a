/// @file synthesizer_core.cc
/// @brief SynthesizerCore: request validation, batched rendering, background hot swap.
#include "nodes/synthesizer/synthesizer_core.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "convert/image.h"
#include "convert/pose.h"
#include "model/method_registry.h"
#include "msgs/codec.h"
#include "scene/trajectory_io.h"

namespace p2i::nodes {
namespace {

double Ms(SynthesizerCore::Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

int64_t WallNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// The image checks a synthesizer's output must pass before it is put on the wire.
void CheckView(const scene::RgbdSample& v, const std::string& name) {
  if (v.rgb.empty() || v.rgb.type() != CV_8UC3 || v.depth.empty() || v.depth.type() != CV_32FC1 ||
      v.rgb.size() != v.depth.size()) {
    throw std::runtime_error("synthesizer '" + name +
                             "' returned a view without CV_8UC3 rgb and CV_32FC1 depth of one size");
  }
}

}  // namespace

void SynthesizerCoreOptions::Validate() const {
  if (model::FindMethod(method) == nullptr) {
    throw std::invalid_argument("synthesizer: method '" + method + "' is not one of " +
                                model::MethodNames());
  }
  if (max_poses < 1 || max_poses > msgs::kMaxBatch) {
    throw std::invalid_argument("synthesizer: max_poses must be in [1, " +
                                std::to_string(msgs::kMaxBatch) + "] (got " +
                                std::to_string(max_poses) + ")");
  }
  if (max_batch < 1) {
    throw std::invalid_argument("synthesizer: max_batch must be >= 1 (got " +
                                std::to_string(max_batch) + ")");
  }
}

SynthesizerCore::SynthesizerCore(SynthesizerCoreOptions options, SynthesizerLoader loader,
                                 std::shared_ptr<const model::CoverageScorer> coverage)
    : options_(std::move(options)), loader_(std::move(loader)), coverage_(std::move(coverage)) {
  options_.Validate();
  if (!loader_) throw std::invalid_argument("synthesizer: no loader given");
  loader_thread_ = std::thread([this] { LoaderLoop(); });
}

SynthesizerCore::~SynthesizerCore() {
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    stop_ = true;
  }
  pending_cv_.notify_all();
  if (loader_thread_.joinable()) loader_thread_.join();
}

void SynthesizerCore::SetCountHook(std::function<void(const std::string&, uint64_t)> hook) {
  std::lock_guard<std::mutex> lock(counters_mutex_);
  count_hook_ = std::move(hook);
}

void SynthesizerCore::Count(const std::string& key, uint64_t n) {
  std::function<void(const std::string&, uint64_t)> hook;
  {
    std::lock_guard<std::mutex> lock(counters_mutex_);
    counters_[key] += n;
    hook = count_hook_;
  }
  if (hook) hook(key, n);
}

uint64_t SynthesizerCore::Counter(const std::string& key) const {
  std::lock_guard<std::mutex> lock(counters_mutex_);
  auto it = counters_.find(key);
  return it == counters_.end() ? 0 : it->second;
}

std::shared_ptr<SynthesizerCore::Loaded> SynthesizerCore::Current() const {
  std::lock_guard<std::mutex> lock(model_mutex_);
  return current_;
}

bool SynthesizerCore::HasModel() const { return Current() != nullptr; }

uint64_t SynthesizerCore::CurrentVersion() const {
  auto c = Current();
  return c ? c->spec.version : 0;
}

void SynthesizerCore::Install(std::shared_ptr<Loaded> loaded) {
  std::shared_ptr<Loaded> old;
  {
    std::lock_guard<std::mutex> lock(model_mutex_);
    old = std::move(current_);
    current_ = std::move(loaded);
  }
  model_cv_.notify_all();
  // `old` is released here, outside the lock; a request still rendering with it keeps it alive.
}

void SynthesizerCore::LoadNow(const ModelSpec& spec) {
  auto loaded = std::make_shared<Loaded>();
  loaded->spec = spec;
  loaded->synth = loader_(spec);
  if (!loaded->synth) throw std::runtime_error("synthesizer: the loader returned no model");
  loaded->coverage = CoverageFor(spec);
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    newest_requested_ = std::max(newest_requested_, spec.version);
  }
  Install(std::move(loaded));
}

bool SynthesizerCore::SwapAsync(const ModelSpec& spec) {
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    const uint64_t current = CurrentVersion();
    if ((HasModel() && spec.version <= current) ||
        (newest_requested_ > 0 && spec.version <= newest_requested_)) {
      // Re-published (latched) or out-of-order versions: nothing newer to load.
      Count("stale_versions");
      return false;
    }
    newest_requested_ = spec.version;
    pending_ = spec;
  }
  pending_cv_.notify_one();
  return true;
}

std::shared_ptr<const model::CoverageScorer> SynthesizerCore::CoverageFor(const ModelSpec& spec) {
  if (spec.poses_path.empty()) return coverage_;
  try {
    std::vector<scene::Pose> poses;
    for (const auto& p : scene::ReadTumTrajectory(spec.poses_path, scene::TumStampOrder::kSort))
      poses.push_back(p.pose);
    return std::make_shared<const model::CoverageScorer>(std::move(poses));
  } catch (const std::exception& e) {
    {
      std::lock_guard<std::mutex> lock(pending_mutex_);
      last_swap_error_ = "model version " + std::to_string(spec.version) +
                         ": training poses unusable, coverage from the start-up data instead: " +
                         e.what();
    }
    Count("coverage_fallbacks");
    return coverage_;
  }
}

std::string SynthesizerCore::LastSwapError() {
  std::lock_guard<std::mutex> lock(pending_mutex_);
  return last_swap_error_;
}

bool SynthesizerCore::WaitForVersion(uint64_t version,
                                     std::chrono::milliseconds timeout) const {
  std::unique_lock<std::mutex> lock(model_mutex_);
  return model_cv_.wait_for(lock, timeout,
                            [&] { return current_ && current_->spec.version >= version; });
}

void SynthesizerCore::LoaderLoop() {
  for (;;) {
    ModelSpec spec;
    {
      std::unique_lock<std::mutex> lock(pending_mutex_);
      pending_cv_.wait(lock, [this] { return stop_ || pending_.has_value(); });
      if (stop_) return;
      spec = *pending_;
      pending_.reset();
      loading_ = true;
    }
    try {
      auto loaded = std::make_shared<Loaded>();
      loaded->spec = spec;
      loaded->synth = loader_(spec);
      if (!loaded->synth) throw std::runtime_error("the loader returned no model");
      loaded->coverage = CoverageFor(spec);
      if (spec.version > CurrentVersion() || !HasModel()) {
        Install(std::move(loaded));
        Count("swaps");
      } else {
        Count("stale_versions");
      }
    } catch (const std::exception& e) {
      {
        // A version that failed to load must not block the ones after it: a bogus announcement
        // (say version 1000 with a missing file) would otherwise make every real version up to
        // 1000 "stale". Forget it unless something newer is already pending.
        std::lock_guard<std::mutex> lock(pending_mutex_);
        if (!pending_ && newest_requested_ == spec.version) newest_requested_ = CurrentVersion();
        last_swap_error_ = "model version " + std::to_string(spec.version) + " (" +
                           spec.checkpoint_path + "): " + e.what();
      }
      Count("swap_failures");
    }
    loading_ = false;
  }
}

bool SynthesizerCore::ToScenePose(const msgs::pb::Pose& pose, const std::string& field,
                                  scene::Pose* out, std::string* why) {
  msgs::pb::Pose checked = pose;  // the codec's rule (finite, unit quaternion), normalised
  if (!msgs::ValidatePose(&checked, field, why)) return false;
  *out = convert::FromMsg(checked);
  return true;
}

std::vector<SynthesizerCore::Rendered> SynthesizerCore::RenderWith(
    Loaded* loaded, const std::vector<scene::Pose>& poses, Clock::time_point receipt) {
  std::vector<Rendered> out;
  out.reserve(poses.size());
  std::lock_guard<std::mutex> lock(loaded->render_mutex);
  const std::string name = loaded->synth->Name();
  for (size_t begin = 0; begin < poses.size(); begin += options_.max_batch) {
    const size_t end = std::min(poses.size(), begin + static_cast<size_t>(options_.max_batch));
    std::vector<scene::Pose> chunk(poses.begin() + begin, poses.begin() + end);
    const Clock::time_point start = Clock::now();
    std::vector<scene::RgbdSample> views = loaded->synth->RenderBatch(chunk);
    const Clock::time_point stop = Clock::now();
    if (views.size() != chunk.size()) {
      throw std::runtime_error("synthesizer '" + name + "' returned " +
                               std::to_string(views.size()) + " views for " +
                               std::to_string(chunk.size()) + " poses");
    }
    const std::vector<model::ViewGeometry> geometry = loaded->synth->LastGeometry();
    for (size_t i = 0; i < views.size(); ++i) {
      CheckView(views[i], name);
      Rendered r;
      r.view = std::move(views[i]);
      r.queue_ms = Ms(start - receipt);
      r.render_ms = Ms(stop - start) / static_cast<double>(chunk.size());
      if (geometry.size() == views.size()) r.geometry = geometry[i];
      out.push_back(std::move(r));
    }
  }
  return out;
}

void SynthesizerCore::FillMeta(const Loaded& loaded, const msgs::pb::Pose& pose_msg,
                               const scene::Pose& pose, const Rendered& r,
                               msgs::pb::ViewMeta* meta) const {
  *meta->mutable_pose() = pose_msg;
  meta->set_model_version(loaded.spec.version);
  meta->set_coverage(loaded.coverage ? loaded.coverage->Score(pose) : 0.0);
  meta->set_queue_ms(r.queue_ms);
  meta->set_render_ms(r.render_ms);
  meta->set_method(options_.method);
  if (r.geometry) {
    meta->set_observed_fraction(std::clamp(r.geometry->observed_fraction, 0.0, 1.0));
    meta->set_keyframe_angle_deg(std::clamp(r.geometry->keyframe_angle_deg, 0.0, 180.0));
  }
}

void SynthesizerCore::HandleRender(const msgs::pb::RenderRequest& request,
                                   Clock::time_point receipt, msgs::RenderReplyMsg* reply) {
  reply->meta.Clear();
  reply->images.clear();
  reply->meta.set_request_id(request.request_id());
  reply->meta.set_ok(false);
  Count("requests");
  auto refuse = [&](const std::string& counter, const std::string& error) {
    Count(counter);
    reply->meta.set_error(error);
    reply->meta.clear_views();
    reply->images.clear();
  };

  if (request.poses_size() == 0) return refuse("bad_requests", "request has no poses");
  if (request.poses_size() > options_.max_poses) {
    return refuse("bad_requests", "request has " + std::to_string(request.poses_size()) +
                                      " poses, more than max_poses " +
                                      std::to_string(options_.max_poses));
  }
  if (!request.method().empty() && request.method() != options_.method) {
    return refuse("bad_requests", "method '" + request.method() + "' is not served here (this "
                                  "synthesizer serves '" + options_.method + "')");
  }
  std::vector<scene::Pose> poses(static_cast<size_t>(request.poses_size()));
  for (int i = 0; i < request.poses_size(); ++i) {
    std::string why;
    if (!ToScenePose(request.poses(i), "poses[" + std::to_string(i) + "]", &poses[i], &why)) {
      return refuse("bad_requests", why);
    }
  }
  if (request.deadline_ns() > 0 && WallNowNs() > request.deadline_ns()) {
    return refuse("expired", "deadline passed before rendering started");
  }
  // One reference for the whole request: every view comes from the same model.
  std::shared_ptr<Loaded> loaded = Current();
  if (!loaded) return refuse("no_model", "no model loaded yet (waiting for a ModelVersion)");
  try {
    std::vector<Rendered> rendered = RenderWith(loaded.get(), poses, receipt);
    for (size_t i = 0; i < rendered.size(); ++i) {
      FillMeta(*loaded, request.poses(static_cast<int>(i)), poses[i], rendered[i],
               reply->meta.add_views());
      reply->images.push_back(convert::ToImage(rendered[i].view.rgb));
      reply->images.push_back(convert::ToImage(rendered[i].view.depth));
    }
  } catch (const std::exception& e) {
    return refuse("render_errors", std::string("render failed: ") + e.what());
  }
  reply->meta.set_ok(true);
  Count("views", static_cast<uint64_t>(reply->meta.views_size()));
}

bool SynthesizerCore::RenderView(const msgs::pb::Pose& pose, Clock::time_point receipt,
                                 msgs::View* view, std::string* error) {
  std::string why;
  scene::Pose scene_pose;
  if (!ToScenePose(pose, "pose", &scene_pose, &why)) {
    Count("bad_requests");
    *error = why;
    return false;
  }
  std::shared_ptr<Loaded> loaded = Current();
  if (!loaded) {
    Count("no_model");
    *error = "no model loaded yet (waiting for a ModelVersion)";
    return false;
  }
  try {
    std::vector<Rendered> rendered = RenderWith(loaded.get(), {scene_pose}, receipt);
    msgs::pb::ViewMeta meta;
    FillMeta(*loaded, pose, scene_pose, rendered[0], &meta);
    view->meta.Clear();
    *view->meta.mutable_pose() = meta.pose();
    view->meta.set_model_version(meta.model_version());
    view->meta.set_coverage(meta.coverage());
    view->meta.set_queue_ms(meta.queue_ms());
    view->meta.set_render_ms(meta.render_ms());
    view->meta.set_method(meta.method());
    if (meta.has_observed_fraction()) view->meta.set_observed_fraction(meta.observed_fraction());
    if (meta.has_keyframe_angle_deg()) view->meta.set_keyframe_angle_deg(meta.keyframe_angle_deg());
    view->rgb = convert::ToImage(rendered[0].view.rgb);
    view->depth = convert::ToImage(rendered[0].view.depth);
  } catch (const std::exception& e) {
    Count("render_errors");
    *error = std::string("render failed: ") + e.what();
    return false;
  }
  Count("views");
  return true;
}

}  // namespace p2i::nodes
