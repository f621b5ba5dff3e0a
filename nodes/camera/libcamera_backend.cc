/// @file libcamera_backend.cc
/// @brief The libcamera live backend. Compiled with libcamera only when CMake found it
/// (P2I_HAVE_LIBCAMERA); otherwise OpenLibcameraBackend says so.
#include "nodes/camera/live_backend.h"

#include <stdexcept>

#ifdef P2I_HAVE_LIBCAMERA
#error "todo"
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
