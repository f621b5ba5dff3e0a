/// @file libcamera_backend.cc
/// @brief The libcamera live backend. Compiled with libcamera only when CMake found it
/// (P2I_HAVE_LIBCAMERA); otherwise OpenLibcameraBackend says so.
#include "nodes/camera/live_backend.h"

#include <stdexcept>

#ifdef P2I_HAVE_LIBCAMERA

#include <sys/mman.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <vector>

#include <libcamera/libcamera.h>
#include <opencv2/imgproc.hpp>

namespace p2i::nodes {
namespace {

namespace lc = libcamera;

/// Bytes per pixel and the cvtColor code to RGB of the RGB formats accepted, or 0 if another.
/// libcamera names follow DRM fourccs (little-endian words): BGR888 is R G B in memory.
int RgbLayout(const lc::PixelFormat& f, int* code) {
  if (f == lc::formats::BGR888) { *code = -1; return 3; }  // already R G B
  if (f == lc::formats::RGB888) { *code = cv::COLOR_BGR2RGB; return 3; }
  if (f == lc::formats::XBGR8888) { *code = cv::COLOR_RGBA2RGB; return 4; }
  if (f == lc::formats::XRGB8888) { *code = cv::COLOR_BGRA2RGB; return 4; }
  return 0;
}

class LibcameraBackend : public LiveBackend {
 public:
  // Options checked by CameraOptions::Validate (buffers >= 2).
  explicit LibcameraBackend(const LibcameraOptions& o) {
    manager_ = std::make_unique<lc::CameraManager>();
    if (manager_->start() != 0) {
      throw std::runtime_error("libcamera: cannot start the camera manager");
    }
    const auto cameras = manager_->cameras();
    if (cameras.empty()) {
      throw std::runtime_error(
          "libcamera: no camera found (is one connected and enabled, and may this user open "
          "/dev/media* and /dev/video*?)");
    }
    if (o.camera.empty()) {
      camera_ = cameras.front();
    } else {
      camera_ = manager_->get(o.camera);
      if (!camera_) {
        std::string found;
        for (const auto& c : cameras) found += (found.empty() ? "'" : ", '") + c->id() + "'";
        throw std::runtime_error("libcamera: camera '" + o.camera + "' not found; cameras: " +
                                 found);
      }
    }
    id_ = camera_->id();
    if (camera_->acquire() != 0) {
      throw std::runtime_error("libcamera: camera '" + id_ + "' is in use by another process");
    }
    acquired_ = true;
    config_ = camera_->generateConfiguration({lc::StreamRole::Viewfinder});
    if (!config_ || config_->size() == 0) {
      throw std::runtime_error("libcamera: camera '" + id_ + "' has no viewfinder stream");
    }
    lc::StreamConfiguration& sc = config_->at(0);
    sc.pixelFormat = lc::formats::BGR888;
    if (o.width > 0 && o.height > 0) sc.size = lc::Size(o.width, o.height);
    sc.bufferCount = static_cast<unsigned>(o.buffers);
    if (config_->validate() == lc::CameraConfiguration::Invalid) {
      throw std::runtime_error("libcamera: camera '" + id_ + "' rejects " + sc.toString());
    }
    if (RgbLayout(sc.pixelFormat, &code_) == 0) {
      throw std::runtime_error("libcamera: camera '" + id_ + "' offers no RGB viewfinder format (" +
                               sc.pixelFormat.toString() + "); p2i converts BGR888, RGB888, "
                               "XBGR8888, XRGB8888");
    }
    bpp_ = RgbLayout(sc.pixelFormat, &code_);
    if (camera_->configure(config_.get()) != 0) {
      throw std::runtime_error("libcamera: camera '" + id_ + "': configure " + sc.toString() +
                               " failed");
    }
    width_ = static_cast<int>(sc.size.width);
    height_ = static_cast<int>(sc.size.height);
    stride_ = sc.stride;
    format_name_ = sc.pixelFormat.toString();
    stream_ = sc.stream();
    allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
    if (allocator_->allocate(stream_) < 0) {
      throw std::runtime_error("libcamera: camera '" + id_ + "': cannot allocate buffers");
    }
    for (const std::unique_ptr<lc::FrameBuffer>& buffer : allocator_->buffers(stream_)) {
      const lc::FrameBuffer::Plane& plane = buffer->planes().front();
      const size_t length = plane.offset + plane.length;
      void* map = mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (map == MAP_FAILED) {
        throw std::runtime_error("libcamera: camera '" + id_ + "': cannot map a buffer");
      }
      maps_.push_back(Mapping{buffer.get(), static_cast<uint8_t*>(map), length, plane.offset});
      std::unique_ptr<lc::Request> request = camera_->createRequest();
      if (!request || request->addBuffer(stream_, buffer.get()) != 0) {
        throw std::runtime_error("libcamera: camera '" + id_ + "': cannot create a request");
      }
      requests_.push_back(std::move(request));
    }
  }

  ~LibcameraBackend() override {
    Stop();
    requests_.clear();
    for (const Mapping& m : maps_) munmap(m.base, m.length);
    if (allocator_) allocator_->free(stream_);
    allocator_.reset();
    if (acquired_) camera_->release();
    camera_.reset();
    if (manager_) manager_->stop();
  }

  void Start(FrameCallback on_frame, ErrorCallback on_error) override {
    if (running_) return;
    on_frame_ = std::move(on_frame);
    on_error_ = std::move(on_error);
    camera_->requestCompleted.connect(this, &LibcameraBackend::OnRequestCompleted);
    camera_->disconnected.connect(this, &LibcameraBackend::OnDisconnected);
    stopping_ = false;
    if (camera_->start() != 0) {
      throw std::runtime_error("libcamera: camera '" + id_ + "': start failed");
    }
    running_ = true;
    for (const auto& r : requests_) camera_->queueRequest(r.get());
  }

  void Stop() override {
    if (!running_) return;
    stopping_ = true;
    camera_->stop();  // completes (cancels) every queued request before it returns
    camera_->requestCompleted.disconnect(this, &LibcameraBackend::OnRequestCompleted);
    camera_->disconnected.disconnect(this, &LibcameraBackend::OnDisconnected);
    running_ = false;
  }

  std::string Describe() const override {
    return "libcamera camera '" + id_ + "' " + std::to_string(width_) + "x" +
           std::to_string(height_) + " " + format_name_;
  }
  int width() const override { return width_; }
  int height() const override { return height_; }
  Stats GetStats() const override {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    return stats_;
  }

 private:
  struct Mapping {
    const lc::FrameBuffer* buffer;
    uint8_t* base;
    size_t length;
    size_t offset;
  };

  /// On libcamera's thread (camera unplugged).
  void OnDisconnected() {
    if (!stopping_) on_error_("libcamera: camera '" + id_ + "' disconnected");
  }

  /// On libcamera's thread.
  void OnRequestCompleted(lc::Request* request) {
    if (request->status() == lc::Request::RequestCancelled || stopping_) return;
    const lc::FrameBuffer* buffer = request->buffers().begin()->second;
    const lc::FrameMetadata& md = buffer->metadata();
    bool ok = md.status == lc::FrameMetadata::FrameSuccess;
    if (ok) {
      for (const Mapping& m : maps_) {
        if (m.buffer != buffer) continue;
        const cv::Mat in(height_, width_, bpp_ == 3 ? CV_8UC3 : CV_8UC4, m.base + m.offset,
                         stride_);
        LiveFrame frame;
        // The sensor timestamp is CLOCK_MONOTONIC (steady_clock); move it to the system clock.
        const int64_t mono_now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                     std::chrono::steady_clock::now().time_since_epoch()).count();
        const int64_t sys_now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                    std::chrono::system_clock::now().time_since_epoch()).count();
        frame.stamp_ns = static_cast<int64_t>(md.timestamp) + (sys_now - mono_now);
        frame.frame_id = md.sequence;
        if (code_ < 0) {
          frame.rgb = in.clone();
        } else {
          cv::cvtColor(in, frame.rgb, code_);
        }
        {
          std::lock_guard<std::mutex> lock(stats_mutex_);
          ++stats_.frames;
        }
        on_frame_(std::move(frame));
        break;
      }
    } else {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++stats_.incomplete;
    }
    request->reuse(lc::Request::ReuseBuffers);
    if (!stopping_) camera_->queueRequest(request);
  }

  std::unique_ptr<lc::CameraManager> manager_;
  std::shared_ptr<lc::Camera> camera_;
  std::unique_ptr<lc::CameraConfiguration> config_;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  std::vector<Mapping> maps_;
  lc::Stream* stream_ = nullptr;
  std::string id_, format_name_;
  int width_ = 0, height_ = 0, bpp_ = 3, code_ = -1;
  unsigned stride_ = 0;
  bool acquired_ = false, running_ = false;
  std::atomic<bool> stopping_{false};
  FrameCallback on_frame_;
  ErrorCallback on_error_;
  mutable std::mutex stats_mutex_;
  Stats stats_;
};

}  // namespace

bool HaveLibcamera() { return true; }

std::unique_ptr<LiveBackend> OpenLibcameraBackend(const LibcameraOptions& options) {
  return std::make_unique<LibcameraBackend>(options);
}

}  // namespace p2i::nodes

#else  // !P2I_HAVE_LIBCAMERA

namespace p2i::nodes {

bool HaveLibcamera() { return false; }

std::unique_ptr<LiveBackend> OpenLibcameraBackend(const LibcameraOptions&) {
  throw std::runtime_error(
      "backend 'libcamera': this p2i was built without libcamera; install libcamera-dev "
      "(pkg-config libcamera) and rebuild");
}

}  // namespace p2i::nodes

#endif  // P2I_HAVE_LIBCAMERA
