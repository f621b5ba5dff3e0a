/// @file image.cc
/// @brief Image helpers.
#include "msgs/image.h"

#include <memory>

namespace p2i::msgs {

int ChannelCount(Encoding encoding) {
  switch (encoding) {
    case pb::RGB8: return 3;
    case pb::MONO8:
    case pb::MONO16:
    case pb::DEPTH16U:
    case pb::DEPTH32F: return 1;
    default: return 0;
  }
}

int ElementSize(Encoding encoding) {
  switch (encoding) {
    case pb::RGB8:
    case pb::MONO8: return 1;
    case pb::MONO16:
    case pb::DEPTH16U: return 2;
    case pb::DEPTH32F: return 4;
    default: return 0;
  }
}

const char* EncodingName(Encoding encoding) {
  switch (encoding) {
    case pb::RGB8: return "RGB8";
    case pb::MONO8: return "MONO8";
    case pb::MONO16: return "MONO16";
    case pb::DEPTH16U: return "DEPTH16U";
    case pb::DEPTH32F: return "DEPTH32F";
    case pb::ENCODING_UNKNOWN: return "NONE";
    default: return "UNKNOWN_ENCODING";
  }
}

Image Image::Allocate(Encoding encoding, uint32_t width, uint32_t height) {
  Image image;
  image.encoding = encoding;
  image.width = width;
  image.height = height;
  image.step = width * static_cast<uint32_t>(ChannelCount(encoding) * ElementSize(encoding));
  image.data = std::make_shared<const Bytes>(static_cast<size_t>(image.step) * height, 0);
  return image;
}

}  // namespace p2i::msgs
