/// @file image.cc
/// @brief Image helpers and plain-double pose access.
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

void SetPose(const std::array<double, 7>& v, pb::Pose* pose) {
  auto* p = pose->mutable_position();
  p->set_x(v[0]);
  p->set_y(v[1]);
  p->set_z(v[2]);
  auto* q = pose->mutable_orientation();
  q->set_x(v[3]);
  q->set_y(v[4]);
  q->set_z(v[5]);
  q->set_w(v[6]);
}

std::array<double, 7> PoseVector(const pb::Pose& pose) {
  const auto& p = pose.position();
  const auto& q = pose.orientation();
  return {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()};
}

}  // namespace p2i::msgs
