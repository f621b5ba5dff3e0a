/// @file zmq_context.h
/// @brief The one ZeroMQ context of the process.
#pragma once

#include <zmq.hpp>

namespace p2i::runtime {

/// Process-wide ZeroMQ context (2 I/O threads: enough for ~1 GB/s of frames on loopback).
/// Thread-safe (zmq contexts are). Sockets created from it are NOT thread-safe.
zmq::context_t& ZmqContext();

}  // namespace p2i::runtime
