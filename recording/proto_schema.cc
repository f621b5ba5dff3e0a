/// @file proto_schema.cc
/// @brief FileDescriptorSet construction and the MsgType -> descriptor table.
#include "recording/proto_schema.h"

#include <set>

#include <google/protobuf/descriptor.pb.h>

namespace p2i::recording {

namespace gp = google::protobuf;

namespace {

void AddFile(const gp::FileDescriptor* f, std::set<std::string>* seen, gp::FileDescriptorSet* out) {
  if (!seen->insert(f->name()).second) return;
  for (int i = 0; i < f->dependency_count(); ++i) AddFile(f->dependency(i), seen, out);
  f->CopyTo(out->add_file());
}

}  // namespace

std::string FileDescriptorSetFor(const gp::Descriptor* type) {
  gp::FileDescriptorSet set;
  std::set<std::string> seen;
  AddFile(type->file(), &seen, &set);
  return set.SerializeAsString();
}

const gp::Descriptor* DescriptorOf(msgs::pb::MsgType type) {
  namespace pb = msgs::pb;
  switch (type) {
    case pb::POSE: return pb::PoseStamped::descriptor();
    case pb::CAMERA_INFO: return pb::CameraInfo::descriptor();
    case pb::RGBD_FRAME: return pb::RgbdFrame::descriptor();
    case pb::POSE_REQUEST: return pb::PoseRequest::descriptor();
    case pb::VIEW: return pb::View::descriptor();
    case pb::MODEL_VERSION: return pb::ModelVersion::descriptor();
    case pb::TRAINER_STATUS: return pb::TrainerStatus::descriptor();
    case pb::NODE_STATUS: return pb::NodeStatus::descriptor();
    case pb::RENDER_REQUEST: return pb::RenderRequest::descriptor();
    case pb::RENDER_REPLY: return pb::RenderReply::descriptor();
    default: return nullptr;
  }
}

const gp::Descriptor* FindDescriptor(const std::string& full_name) {
  return gp::DescriptorPool::generated_pool()->FindMessageTypeByName(full_name);
}

}  // namespace p2i::recording
