/// @file runtime_test_node.cc
/// @brief A small real node for the runtime's multi-process tests: publishes PoseStamped on
/// "chatter", a latched CameraInfo on "camera_info", serves "echo" (PoseRequest -> PoseStamped)
/// and writes `shutdown_marker` (if set) from OnShutdown().
#include <fstream>

#include "nodes/runtime/node.h"

namespace {

using namespace p2i;

class RuntimeTestNode : public runtime::Node {
 public:
  explicit RuntimeTestNode(const runtime::NodeArgs& args) : Node("test_node", args) {
    const double rate = Declare<double>("rate", 50.0, "chatter messages per second");
    frame_id_ = Declare<std::string>("frame_id", "test", "frame_id of chatter messages");
    marker_ = Declare<std::string>("shutdown_marker", "", "file written by OnShutdown()");
    chatter_ = Advertise<msgs::pb::PoseStamped>("chatter");
    runtime::PublisherOptions latched;
    latched.latched = true;
    info_ = Advertise<msgs::pb::CameraInfo>("camera_info", latched);
    server_ = Serve<msgs::pb::PoseRequest, msgs::pb::PoseStamped>(
        "echo", [this](const msgs::pb::PoseRequest& req, msgs::pb::PoseStamped* rep,
                       std::string*) {
          *rep->mutable_pose() = req.pose();
          rep->mutable_header()->set_frame_id(frame_id_);
          Count("echoed");
          return true;
        });
    AddTimer(std::chrono::duration_cast<std::chrono::nanoseconds>(
                 std::chrono::duration<double>(1.0 / rate)),
             [this] { PublishChatter(); });
    msgs::pb::CameraInfo info;
    info.set_width(640);
    info.set_height(480);
    info.set_camera_name("test_camera");
    info.set_distortion_model("plumb_bob");
    for (double k : {585.0, 0.0, 320.0, 0.0, 585.0, 240.0, 0.0, 0.0, 1.0}) info.add_k(k);
    info_->Publish(info);
  }

 protected:
  void OnShutdown() override {
    if (!marker_.empty()) std::ofstream(marker_) << "clean shutdown after " << sent_ << "\n";
  }

 private:
  void PublishChatter() {
    msgs::pb::PoseStamped m;
    m.mutable_header()->set_frame_id(frame_id_);
    m.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
    auto* p = m.mutable_pose();
    p->mutable_position()->set_x(static_cast<double>(sent_));
    p->mutable_orientation()->set_w(1.0);
    p->set_parent_frame("world");
    p->set_child_frame("camera");
    chatter_->Publish(m);
    ++sent_;
  }

  std::string frame_id_, marker_;
  uint64_t sent_ = 0;
  std::shared_ptr<runtime::Publisher<msgs::pb::PoseStamped>> chatter_;
  std::shared_ptr<runtime::Publisher<msgs::pb::CameraInfo>> info_;
  std::shared_ptr<runtime::RawServiceServer> server_;
};

}  // namespace

int main(int argc, char** argv) { return p2i::runtime::RunNode<RuntimeTestNode>(argc, argv); }
