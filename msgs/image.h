/// @file image.h
/// @brief The C++ side of image-carrying messages: an Image is metadata plus a blob frame.
#pragma once

#include <cstdint>
#include <vector>

#include "msgs/p2i.pb.h"
#include "msgs/wire.h"

namespace p2i::msgs {

using Encoding = pb::Encoding;

/// One image travelling as its own blob frame. A value type (the blob is shared and immutable):
/// thread-compatible. Row-major, `step` bytes per row; `data->size()` must be height * step.
struct Image {
  Encoding encoding = pb::ENCODING_UNKNOWN;
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t step = 0;           ///< bytes per row; 0 in Encode means "packed" (width * pixel bytes)
  double depth_scale = 1.0;    ///< metres per unit (depth encodings)
  double invalid_value = 0.0;  ///< raw value meaning "no measurement" (depth encodings)
  Blob data;

  /// A packed image that owns a fresh zeroed buffer of height * width * pixel bytes.
  static Image Allocate(Encoding encoding, uint32_t width, uint32_t height);
  /// Writable pointer to the bytes, for filling an image made by Allocate() before it is sent.
  uint8_t* MutableData() const { return data ? const_cast<uint8_t*>(data->data()) : nullptr; }
};

/// Channels per pixel of an encoding (0 for ENCODING_UNKNOWN / unknown values).
int ChannelCount(Encoding encoding);
/// Bytes per channel of an encoding (0 for ENCODING_UNKNOWN / unknown values).
int ElementSize(Encoding encoding);
/// "RGB8", "DEPTH32F", ...
const char* EncodingName(Encoding encoding);

/// The three structs below are value types (copying shares the immutable blobs):
/// thread-compatible.
///
/// An RGB-D camera frame: metadata (header, camera info or id, optional pose) and two images.
/// meta.rgb / meta.depth are overwritten from `rgb` / `depth` by Encode and filled by Decode.
struct RgbdFrame {
  pb::RgbdFrame meta;
  Image rgb;    ///< RGB8
  Image depth;  ///< DEPTH16U or DEPTH32F
};

/// A synthesised RGB-D view: metadata (header, pose, model version, coverage, timings, method)
/// and two images. meta.rgb / meta.depth are managed by Encode/Decode as for RgbdFrame.
struct View {
  pb::View meta;
  Image rgb;    ///< RGB8
  Image depth;  ///< DEPTH32F or DEPTH16U
};

/// A RenderReply with the images of its views: images[2*i] is the RGB8 image of meta.views(i),
/// images[2*i+1] its depth image. `images` is either empty (error replies, metadata only) or
/// exactly 2 * meta.views_size() long.
struct RenderReplyMsg {
  pb::RenderReply meta;
  std::vector<Image> images;
};

}  // namespace p2i::msgs
