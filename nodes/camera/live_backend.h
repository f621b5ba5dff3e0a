/// @file live_backend.h
/// @brief The interface of live camera backends (Aravis, libcamera) as the camera node sees it:
/// no Aravis/glib or libcamera header appears here.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

namespace p2i::nodes {

/// One frame from a live device, already converted.
struct LiveFrame {
  int64_t stamp_ns = 0;  ///< capture stamp, system clock (runtime::NowNs epoch)
  uint64_t frame_id = 0;  ///< the device's frame counter (0 if unknown)
  cv::Mat rgb;            ///< CV_8UC3, RGB order
  cv::Mat depth;          ///< CV_32FC1 metres (0 invalid), same size as rgb; empty = no depth
};

/// A streaming device. Open (the factory) configures it and throws std::runtime_error naming the
/// device and the problem; Start() begins streaming on the backend's own worker thread, which
/// calls `on_frame` for every complete frame and `on_error` once if the device fails (lost,
/// stream error); both callbacks must be thread-safe and quick. Stop() (also in the destructor)
/// ends streaming and joins the worker; no callback runs after it returns.
///
/// Thread-safety: Start/Stop/accessors from one (the owner's) thread; callbacks on the worker.
class LiveBackend {
 public:
  using FrameCallback = std::function<void(LiveFrame&&)>;
  using ErrorCallback = std::function<void(const std::string&)>;
  /// Counters of the worker (read with Stats(); thread-safe).
  struct Stats {
    uint64_t frames = 0;             ///< frames delivered
    uint64_t incomplete = 0;         ///< buffers dropped by the device/stream (status != ok)
    uint64_t depth_unmatched = 0;    ///< colour frames sent without a depth frame
  };

  virtual ~LiveBackend() = default;
  virtual void Start(FrameCallback on_frame, ErrorCallback on_error) = 0;
  virtual void Stop() = 0;
  /// "aravis device 'Fake_1' (Aravis Fake, 64x48 Mono8)" and the like.
  virtual std::string Describe() const = 0;
  virtual int width() const = 0;
  virtual int height() const = 0;
  virtual Stats GetStats() const = 0;
};

/// Parameters of the Aravis backend (camera_node.h documents them as node parameters).
struct AravisOptions {
  std::string device;          ///< Aravis device id, IP address or "" (the first found)
  std::string pixel_format;    ///< "" = as configured; Mono8, Mono16, RGB8, BGR8, Bayer*8
  int width = 0, height = 0;   ///< 0 = as configured
  double frame_rate = 0.0;     ///< Hz; 0 = as configured
  double exposure_us = 0.0;    ///< 0 = as configured
  std::string depth_device;    ///< optional second device streaming Mono16 depth
  double depth_scale = 0.001;  ///< metres per depth unit
  double depth_tolerance = 0.02;  ///< s: max stamp difference to pair colour and depth
  int buffers = 8;             ///< stream buffers per device
};

/// Opens and configures the device(s). Throws std::runtime_error naming the device and the
/// problem (not found: the devices found are listed; a feature or value the device lacks), or
/// "built without Aravis" when this build has no Aravis.
std::unique_ptr<LiveBackend> OpenAravisBackend(const AravisOptions& options);
bool HaveAravis();

struct LibcameraOptions {
  std::string camera;         ///< libcamera camera id; "" = the first
  int width = 0, height = 0;  ///< 0 = the camera's default for the viewfinder role
  int buffers = 4;
};

/// Like OpenAravisBackend: "built without libcamera; ..." or "no camera found" errors.
std::unique_ptr<LiveBackend> OpenLibcameraBackend(const LibcameraOptions& options);
bool HaveLibcamera();

}  // namespace p2i::nodes
