/// @file wire_io.h
/// @brief Sending and receiving WireMessages as ZeroMQ multipart messages (blobs zero-copy).
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "msgs/wire.h"

namespace p2i::runtime {

/// Sends `m.header` then each blob as its own frame, after the caller has sent its leading
/// frames with sndmore. Blobs are not copied: each frame holds a reference to the shared_ptr
/// until ZeroMQ has sent it. Returns false if the socket would block (`flags` may contain
/// dontwait) — then nothing more is sent.
bool SendWire(zmq::socket_t& socket, const msgs::WireMessage& m,
              zmq::send_flags flags = zmq::send_flags::none);

/// zmq::poll that treats EINTR (a signal arrived, e.g. SIGTERM) as "nothing ready" instead of
/// throwing; callers then see the shutdown flag. Other errors still throw zmq::error_t.
int Poll(zmq::pollitem_t* items, size_t count, std::chrono::milliseconds timeout);

/// Zero-copy frame of a blob (the frame keeps the shared_ptr alive).
zmq::message_t BlobFrame(const msgs::Blob& blob);

/// Receives every remaining frame of the current multipart message (after `first` if given).
/// Never blocks once the first frame has arrived (multipart messages are atomic).
void RecvRest(zmq::socket_t& socket, std::vector<zmq::message_t>* frames);

/// Builds a WireMessage from frames [begin, end): frames[begin] is the header, the rest blobs
/// (copied into owned buffers). Returns false if there is no header frame.
bool FramesToWire(std::vector<zmq::message_t>& frames, size_t begin, msgs::WireMessage* out);

}  // namespace p2i::runtime
