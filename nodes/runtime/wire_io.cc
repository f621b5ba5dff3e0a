/// @file wire_io.cc
/// @brief Multipart send/receive of WireMessages.
#include "nodes/runtime/wire_io.h"

#include <cerrno>

namespace p2i::runtime {
namespace {

void FreeBlob(void* /*data*/, void* hint) { delete static_cast<msgs::Blob*>(hint); }

}  // namespace

int Poll(zmq::pollitem_t* items, size_t count, std::chrono::milliseconds timeout) {
  try {
    return zmq::poll(items, count, timeout);
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) {
      for (size_t i = 0; i < count; ++i) items[i].revents = 0;
      return 0;
    }
    throw;
  }
}

zmq::message_t BlobFrame(const msgs::Blob& blob) {
  if (!blob || blob->empty()) return zmq::message_t();
  auto* holder = new msgs::Blob(blob);
  // const_cast: ZeroMQ's API takes void*, but never writes to data it is given to send.
  return zmq::message_t(const_cast<uint8_t*>(blob->data()), blob->size(), FreeBlob, holder);
}

bool SendWire(zmq::socket_t& socket, const msgs::WireMessage& m, zmq::send_flags flags) {
  const bool has_blobs = !m.blobs.empty();
  auto more = [&](bool last) { return last ? flags : (flags | zmq::send_flags::sndmore); };
  if (!socket.send(zmq::buffer(m.header), more(!has_blobs))) return false;
  for (size_t i = 0; i < m.blobs.size(); ++i) {
    if (!socket.send(BlobFrame(m.blobs[i]), more(i + 1 == m.blobs.size()))) return false;
  }
  return true;
}

void RecvRest(zmq::socket_t& socket, std::vector<zmq::message_t>* frames) {
  while (!frames->empty() && frames->back().more()) {
    zmq::message_t f;
    if (!socket.recv(f, zmq::recv_flags::none)) break;
    frames->push_back(std::move(f));
  }
}

bool FramesToWire(std::vector<zmq::message_t>& frames, size_t begin, msgs::WireMessage* out) {
  if (frames.size() <= begin) return false;
  out->header.assign(static_cast<const char*>(frames[begin].data()), frames[begin].size());
  out->blobs.clear();
  out->blobs.reserve(frames.size() - begin - 1);
  for (size_t i = begin + 1; i < frames.size(); ++i) {
    const auto* p = static_cast<const uint8_t*>(frames[i].data());
    out->blobs.push_back(std::make_shared<const msgs::Bytes>(p, p + frames[i].size()));
  }
  return true;
}

}  // namespace p2i::runtime
