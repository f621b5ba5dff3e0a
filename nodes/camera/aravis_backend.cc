/// @file aravis_backend.cc
/// @brief The Aravis (GigE Vision / USB3 Vision) live backend. Compiled with Aravis only when
/// CMake found aravis-0.8 (P2I_HAVE_ARAVIS); otherwise OpenAravisBackend says so.
#include "nodes/camera/live_backend.h"

#include <stdexcept>

#ifdef P2I_HAVE_ARAVIS

#include <arv.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "nodes/camera/pixel_convert.h"

namespace p2i::nodes {
namespace {

/// The message of a GError (freed), or "" if none.
std::string Take(GError** error) {
  if (*error == nullptr) return "";
  std::string text = (*error)->message != nullptr ? (*error)->message : "unknown error";
  g_clear_error(error);
  return text;
}

/// "'Fake_1' (Aravis Fake, Fake, 0.0.0.0)" for every device found, or "none".
std::string DevicesFound() {
  std::string out;
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    const auto s = [](const char* c) { return std::string(c != nullptr ? c : "?"); };
    out += (out.empty() ? "" : ", ") + ("'" + s(arv_get_device_id(i)) + "' (" +
                                        s(arv_get_device_vendor(i)) + " " +
                                        s(arv_get_device_model(i)) + ", " +
                                        s(arv_get_device_protocol(i)) + " " +
                                        s(arv_get_device_address(i)) + ")");
  }
  return out.empty() ? "none" : out;
}

std::optional<PixelFormat> FromArv(ArvPixelFormat f) {
  switch (f) {
    case ARV_PIXEL_FORMAT_MONO_8: return PixelFormat::kMono8;
    case ARV_PIXEL_FORMAT_MONO_16: return PixelFormat::kMono16;
    case ARV_PIXEL_FORMAT_RGB_8_PACKED: return PixelFormat::kRGB8;
    case ARV_PIXEL_FORMAT_BGR_8_PACKED: return PixelFormat::kBGR8;
    case ARV_PIXEL_FORMAT_BAYER_RG_8: return PixelFormat::kBayerRG8;
    case ARV_PIXEL_FORMAT_BAYER_GR_8: return PixelFormat::kBayerGR8;
    case ARV_PIXEL_FORMAT_BAYER_GB_8: return PixelFormat::kBayerGB8;
    case ARV_PIXEL_FORMAT_BAYER_BG_8: return PixelFormat::kBayerBG8;
    default: return std::nullopt;
  }
}

/// One opened device with its stream. Not copyable; releases everything in its destructor.
class Device {
 public:
  Device(const std::string& requested, const std::string& role) : role_(role) {
    // The in-process fake camera (tests, docs) is only enabled when asked for by name, so that
    // "the first device" never means the fake one; it needs no discovery.
    const bool fake = requested.rfind("Fake", 0) == 0;
    if (fake) arv_enable_interface("Fake");
    id_ = requested;
    std::string open_as = requested;
    if (!fake) {
      arv_update_device_list();  // discovery: about 1 s for GigE Vision
      if (id_.empty()) {
        if (arv_get_n_devices() == 0) {
          throw std::runtime_error(
              "aravis: no GigE Vision / USB3 Vision camera found (check the cable, the network "
              "(GigE cameras must be on a subnet of a local interface) and USB permissions; "
              "set " + role + ":=ID or IP address to choose one)");
        }
        id_ = open_as = arv_get_device_id(0);
      }
      // A GigE camera is opened by its IP address: Aravis then streams through the interface
      // that routes to it. By id it takes the interface whose discovery reply came first, which
      // on a multi-homed host (e.g. a camera on 127.0.0.1) may be one the stream cannot use.
      for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
        const char* id = arv_get_device_id(i);
        const char* protocol = arv_get_device_protocol(i);
        const char* address = arv_get_device_address(i);
        if (id != nullptr && id_ == id && protocol != nullptr &&
            std::string(protocol) == "GigEVision" && address != nullptr && *address != 0) {
          open_as = address;
          break;
        }
      }
    }
    GError* error = nullptr;
    camera_ = arv_camera_new(open_as.c_str(), &error);
    if (camera_ == nullptr) {
      const std::string why = Take(&error);
      arv_update_device_list();
      throw std::runtime_error("aravis: cannot open " + role + " '" + id_ + "': " + why +
                               "; devices found: " + DevicesFound());
    }
    const char* model = arv_camera_get_model_name(camera_, nullptr);
    const char* vendor = arv_camera_get_vendor_name(camera_, nullptr);
    model_ = std::string(vendor != nullptr ? vendor : "?") + " " + (model != nullptr ? model : "?");
    g_signal_connect(arv_camera_get_device(camera_), "control-lost", G_CALLBACK(&OnControlLost),
                     this);
  }
  ~Device() {
    if (camera_ != nullptr) {
      g_signal_handlers_disconnect_by_data(arv_camera_get_device(camera_), this);
      if (acquiring_) arv_camera_stop_acquisition(camera_, nullptr);
    }
    if (stream_ != nullptr) g_object_unref(stream_);
    if (camera_ != nullptr) g_object_unref(camera_);
  }
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  /// Applies the settings; throws naming the device, the setting and what it accepts.
  void Configure(const std::string& pixel_format, int width, int height, double frame_rate,
                 double exposure_us) {
    SetPixelFormat(pixel_format);
    SetSize(width, height);
    GError* error = nullptr;
    if (arv_camera_is_feature_available(camera_, "AcquisitionMode", nullptr)) {
      arv_camera_set_acquisition_mode(camera_, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
      Check(&error, "setting AcquisitionMode to Continuous");
    }
    SetFrameRate(frame_rate);
    SetExposure(exposure_us);
    if (arv_camera_is_gv_device(camera_)) {
      arv_camera_gv_auto_packet_size(camera_, &error);  // best effort; the default also works
      g_clear_error(&error);
    }
    const ArvPixelFormat current = arv_camera_get_pixel_format(camera_, &error);
    Check(&error, "reading the pixel format");
    const auto format = FromArv(current);
    if (!format) {
      const char* name = arv_camera_get_pixel_format_as_string(camera_, nullptr);
      throw std::runtime_error(Name() + ": its pixel format '" + (name != nullptr ? name : "?") +
                               "' cannot be converted; set pixel_format:= one of " +
                               SupportedPixelFormats());
    }
    format_ = *format;
    gint x = 0, y = 0;
    arv_camera_get_region(camera_, &x, &y, &width_, &height_, &error);
    Check(&error, "reading the region");
  }

  void StartStream(int buffers) {
    GError* error = nullptr;
    stream_ = arv_camera_create_stream(camera_, nullptr, nullptr, &error);
    if (stream_ == nullptr) {
      Check(&error, "creating the stream");
      throw std::runtime_error(Name() + ": cannot create a stream");
    }
    const guint payload = arv_camera_get_payload(camera_, &error);
    Check(&error, "reading the payload size");
    for (int i = 0; i < buffers; ++i) {
      arv_stream_push_buffer(stream_, arv_buffer_new(payload, nullptr));
    }
    arv_camera_start_acquisition(camera_, &error);
    Check(&error, "starting acquisition");
    acquiring_ = true;
  }
  void StopStream() {
    if (acquiring_) arv_camera_stop_acquisition(camera_, nullptr);
    acquiring_ = false;
  }

  ArvStream* stream() const { return stream_; }
  PixelFormat format() const { return format_; }
  int width() const { return width_; }
  int height() const { return height_; }
  bool lost() const { return lost_.load(); }
  std::string Name() const { return "aravis " + role_ + " '" + id_ + "' (" + model_ + ")"; }

 private:
  static void OnControlLost(ArvDevice*, gpointer self) {
    static_cast<Device*>(self)->lost_.store(true);
  }
  // pixel_format (empty = keep): one p2i converts and the device offers.
  void SetPixelFormat(const std::string& pixel_format) {
    if (pixel_format.empty()) return;
    GError* error = nullptr;
    if (!ParsePixelFormat(pixel_format)) {
      throw std::runtime_error(Name() + ": pixel_format '" + pixel_format +
                               "' cannot be converted by p2i (supported: " +
                               SupportedPixelFormats() + ")");
    }
    guint n = 0;
    const char** formats =
        arv_camera_dup_available_pixel_formats_as_strings(camera_, &n, &error);
    std::string offered;
    bool found = false;
    for (guint i = 0; formats != nullptr && i < n; ++i) {
      offered += (offered.empty() ? "" : ", ") + std::string(formats[i]);
      found = found || pixel_format == formats[i];
    }
    g_free(formats);
    g_clear_error(&error);
    if (!found) {
      throw std::runtime_error(Name() + " does not offer pixel format '" + pixel_format +
                               "' (it offers: " + (offered.empty() ? "?" : offered) + ")");
    }
    arv_camera_set_pixel_format_from_string(camera_, pixel_format.c_str(), &error);
    Check(&error, "setting PixelFormat to " + pixel_format);
  }

  // The region's size (0 = keep that side), within the device's bounds.
  void SetSize(int width, int height) {
    if (!(width > 0 || height > 0)) return;
    GError* error = nullptr;
    gint min_w = 0, max_w = 0, min_h = 0, max_h = 0;
    arv_camera_get_width_bounds(camera_, &min_w, &max_w, &error);
    Check(&error, "reading the Width bounds");
    arv_camera_get_height_bounds(camera_, &min_h, &max_h, &error);
    Check(&error, "reading the Height bounds");
    gint x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera_, &x, &y, &w, &h, &error);
    Check(&error, "reading the region");
    if (width > 0) w = width;
    if (height > 0) h = height;
    if (w < min_w || w > max_w || h < min_h || h > max_h) {
      throw std::runtime_error(Name() + ": size " + std::to_string(w) + "x" +
                               std::to_string(h) + " is outside the device's range " +
                               std::to_string(min_w) + ".." + std::to_string(max_w) + " x " +
                               std::to_string(min_h) + ".." + std::to_string(max_h));
    }
    arv_camera_set_region(camera_, 0, 0, w, h, &error);
    Check(&error, "setting the size to " + std::to_string(w) + "x" + std::to_string(h));
  }

  // frame_rate (0 = keep the device's), within its bounds.
  void SetFrameRate(double frame_rate) {
    if (!(frame_rate > 0.0)) return;
    GError* error = nullptr;
    if (!arv_camera_is_frame_rate_available(camera_, nullptr)) {
      throw std::runtime_error(Name() + " has no frame rate control (AcquisitionFrameRate); "
                               "use frame_rate:=0 to keep its own rate");
    }
    double lo = 0.0, hi = 0.0;
    arv_camera_get_frame_rate_bounds(camera_, &lo, &hi, &error);
    Check(&error, "reading the frame rate bounds");
    if (frame_rate < lo || frame_rate > hi) {
      throw std::runtime_error(Name() + ": frame_rate " + std::to_string(frame_rate) +
                               " Hz is outside the device's range " + std::to_string(lo) +
                               ".." + std::to_string(hi) + " Hz");
    }
    arv_camera_set_frame_rate(camera_, frame_rate, &error);
    Check(&error, "setting the frame rate");
  }

  // exposure_us (0 = keep the device's), auto exposure off, within its bounds.
  void SetExposure(double exposure_us) {
    if (!(exposure_us > 0.0)) return;
    GError* error = nullptr;
    if (!arv_camera_is_exposure_time_available(camera_, nullptr)) {
      throw std::runtime_error(Name() + " has no exposure time control (ExposureTime); "
                               "use exposure_us:=0 to keep its own exposure");
    }
    if (arv_camera_is_exposure_auto_available(camera_, nullptr)) {
      arv_camera_set_exposure_time_auto(camera_, ARV_AUTO_OFF, &error);
      Check(&error, "switching ExposureAuto off");
    }
    double lo = 0.0, hi = 0.0;
    arv_camera_get_exposure_time_bounds(camera_, &lo, &hi, &error);
    Check(&error, "reading the exposure bounds");
    if (exposure_us < lo || exposure_us > hi) {
      throw std::runtime_error(Name() + ": exposure_us " + std::to_string(exposure_us) +
                               " is outside the device's range " + std::to_string(lo) + ".." +
                               std::to_string(hi) + " us");
    }
    arv_camera_set_exposure_time(camera_, exposure_us, &error);
    Check(&error, "setting the exposure time");
  }

  void Check(GError** error, const std::string& what) {
    if (*error != nullptr) throw std::runtime_error(Name() + ": " + what + ": " + Take(error));
  }

  std::string role_, id_, model_;
  ArvCamera* camera_ = nullptr;
  ArvStream* stream_ = nullptr;
  PixelFormat format_ = PixelFormat::kMono8;
  gint width_ = 0, height_ = 0;
  bool acquiring_ = false;
  std::atomic<bool> lost_{false};
};

struct DepthImage {
  int64_t stamp_ns;
  cv::Mat depth;
};

class AravisBackend : public LiveBackend {
 public:
  // Options checked by CameraOptions::Validate (buffers >= 2, depth_scale > 0).
  explicit AravisBackend(const AravisOptions& o) : options_(o) {
    color_ = std::make_unique<Device>(o.device, "device");
    color_->Configure(o.pixel_format, o.width, o.height, o.frame_rate, o.exposure_us);
    if (!o.depth_device.empty()) {
      depth_ = std::make_unique<Device>(o.depth_device, "depth_device");
      depth_->Configure("Mono16", o.width, o.height, o.frame_rate, 0.0);
    }
  }
  ~AravisBackend() override { Stop(); }

  void Start(FrameCallback on_frame, ErrorCallback on_error) override {
    if (worker_.joinable()) return;
    on_frame_ = std::move(on_frame);
    on_error_ = std::move(on_error);
    color_->StartStream(options_.buffers);
    if (depth_) depth_->StartStream(options_.buffers);
    stop_ = false;
    worker_ = std::thread([this] { Run(); });
  }

  void Stop() override {
    stop_ = true;
    if (worker_.joinable()) worker_.join();
    color_->StopStream();
    if (depth_) depth_->StopStream();
  }

  std::string Describe() const override {
    std::string d = color_->Name() + " " + std::to_string(color_->width()) + "x" +
                    std::to_string(color_->height()) + " " + ToString(color_->format());
    if (depth_) {
      d += " + depth " + depth_->Name() + " " + std::to_string(depth_->width()) + "x" +
           std::to_string(depth_->height()) + " Mono16 x " + std::to_string(options_.depth_scale) +
           " m";
    }
    return d;
  }
  int width() const override { return color_->width(); }
  int height() const override { return color_->height(); }
  Stats GetStats() const override {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    return stats_;
  }

 private:
  /// A converted image from `buffer`, or nullopt (counted) if the buffer is not a good image.
  template <class F>
  bool Convert(ArvBuffer* buffer, F&& convert) {
    if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS) return false;
    size_t size = 0;
    const void* data = arv_buffer_get_image_data(buffer, &size);
    const auto format = FromArv(arv_buffer_get_image_pixel_format(buffer));
    if (data == nullptr || !format) return false;
    convert(static_cast<const uint8_t*>(data), size, arv_buffer_get_image_width(buffer),
            arv_buffer_get_image_height(buffer), *format);
    return true;
  }

  static int64_t Stamp(ArvBuffer* buffer) {
    // Host reception time on the system clock (the pose stream's clock); the device clock is
    // not synchronised with the host in general.
    const guint64 t = arv_buffer_get_system_timestamp(buffer);
    if (t != 0) return static_cast<int64_t>(t);
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  }

  void TakeDepth(ArvBuffer* buffer) {
    bool ok = false;
    try {
      ok = Convert(buffer, [&](const uint8_t* data, size_t size, int w, int h, PixelFormat f) {
        if (f != PixelFormat::kMono16) return;
        depth_ring_.push_back(
            DepthImage{Stamp(buffer), Mono16ToDepth(data, size, w, h, options_.depth_scale)});
        while (depth_ring_.size() > 8) depth_ring_.pop_front();
      });
    } catch (const std::exception&) {
      ok = false;
    }
    if (!ok) Bump(&Stats::incomplete);
    arv_stream_push_buffer(depth_->stream(), buffer);
  }

  /// The depth image nearest to `stamp` within the tolerance, waiting up to the tolerance for
  /// one at or after the stamp.
  cv::Mat PairDepth(int64_t stamp, cv::Size size) {
    const int64_t tol = static_cast<int64_t>(options_.depth_tolerance * 1e9);
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::nanoseconds(tol);
    while (true) {
      while (ArvBuffer* b = arv_stream_try_pop_buffer(depth_->stream())) TakeDepth(b);
      const bool newer = std::any_of(depth_ring_.begin(), depth_ring_.end(),
                                     [&](const DepthImage& d) { return d.stamp_ns >= stamp; });
      const auto now = std::chrono::steady_clock::now();
      if (newer || now >= deadline || stop_) break;
      const auto wait = std::chrono::duration_cast<std::chrono::microseconds>(deadline - now);
      if (ArvBuffer* b = arv_stream_timeout_pop_buffer(depth_->stream(),
                                                       std::max<int64_t>(1, wait.count()))) {
        TakeDepth(b);
      }
    }
    const DepthImage* best = nullptr;
    for (const DepthImage& d : depth_ring_) {
      const int64_t dt = std::llabs(d.stamp_ns - stamp);
      if (dt <= tol && (best == nullptr || dt < std::llabs(best->stamp_ns - stamp))) best = &d;
    }
    if (best == nullptr) return cv::Mat();
    cv::Mat depth = best->depth;
    if (depth.size() != size) {
      cv::Mat resized;
      cv::resize(depth, resized, size, 0, 0, cv::INTER_NEAREST_EXACT);  // centre-aligned (image_ops.cc)
      depth = resized;
    }
    return depth;
  }

  void Run() {
    bool reported = false;
    while (!stop_) {
      if (!reported && (color_->lost() || (depth_ && depth_->lost()))) {
        reported = true;
        on_error_((color_->lost() ? color_->Name() : depth_->Name()) +
                  ": connection lost (control-lost)");
      }
      ArvBuffer* buffer = arv_stream_timeout_pop_buffer(color_->stream(), 100000);
      if (buffer == nullptr) {
        if (depth_) {
          while (ArvBuffer* b = arv_stream_try_pop_buffer(depth_->stream())) TakeDepth(b);
        }
        continue;
      }
      LiveFrame frame;
      frame.stamp_ns = Stamp(buffer);
      frame.frame_id = arv_buffer_get_frame_id(buffer);
      bool ok = false;
      try {
        ok = Convert(buffer, [&](const uint8_t* data, size_t size, int w, int h, PixelFormat f) {
          frame.rgb = ToRgb8(data, size, w, h, f);
        });
      } catch (const std::exception&) {
        ok = false;  // a short or malformed buffer: counted as incomplete
      }
      arv_stream_push_buffer(color_->stream(), buffer);
      if (!ok) {
        Bump(&Stats::incomplete);
        continue;
      }
      if (depth_) {
        frame.depth = PairDepth(frame.stamp_ns, frame.rgb.size());
        if (frame.depth.empty()) Bump(&Stats::depth_unmatched);
      }
      Bump(&Stats::frames);
      on_frame_(std::move(frame));
    }
  }

  void Bump(uint64_t Stats::*field) {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++(stats_.*field);
  }

  AravisOptions options_;
  std::unique_ptr<Device> color_, depth_;
  std::deque<DepthImage> depth_ring_;  // worker thread only
  FrameCallback on_frame_;
  ErrorCallback on_error_;
  std::atomic<bool> stop_{true};
  std::thread worker_;
  mutable std::mutex stats_mutex_;
  Stats stats_;
};

}  // namespace

bool HaveAravis() { return true; }

std::unique_ptr<LiveBackend> OpenAravisBackend(const AravisOptions& options) {
  return std::make_unique<AravisBackend>(options);
}

}  // namespace p2i::nodes

#else  // !P2I_HAVE_ARAVIS

namespace p2i::nodes {

bool HaveAravis() { return false; }

std::unique_ptr<LiveBackend> OpenAravisBackend(const AravisOptions&) {
  throw std::runtime_error(
      "backend 'aravis': this p2i was built without Aravis; install libaravis-dev and "
      "libusb-1.0-0-dev (pkg-config aravis-0.8) and rebuild");
}

}  // namespace p2i::nodes

#endif  // P2I_HAVE_ARAVIS
