/// @file zmq_context.cc
/// @brief The one ZeroMQ context of the process.
#include "nodes/runtime/zmq_context.h"

namespace p2i::runtime {

zmq::context_t& ZmqContext() {
  // Leaked on purpose: destroying a context at static-destruction time blocks on sockets that
  // other statics might still hold; the OS reclaims it at exit.
  static zmq::context_t* ctx = [] {
    auto* c = new zmq::context_t(2);
    c->set(zmq::ctxopt::blocky, false);  // sockets default to linger 0 semantics at term
    return c;
  }();
  return *ctx;
}

}  // namespace p2i::runtime
