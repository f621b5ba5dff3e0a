/// @file param_service.cc
/// @brief File-based parameter service (see param_service.h).
#include "nodes/runtime/param_service.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "nodes/runtime/endpoints.h"
#include "util/yaml_flow.h"

namespace p2i::runtime {
namespace {

namespace fs = std::filesystem;

void WriteAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
    if (!out) return;  // best effort, like the registry
  }
  std::rename(tmp.c_str(), path.c_str());
}

}  // namespace

std::string ParamsDir() { return ParamsDir(RunDir()); }

std::string ParamsDir(const std::string& run_dir) { return run_dir + "/params"; }

std::string ParamsStem(int pid, const std::string& full_node_name) {
  std::string flat = full_node_name;
  while (!flat.empty() && flat[0] == '/') flat.erase(0, 1);
  std::replace(flat.begin(), flat.end(), '/', '.');
  return std::to_string(pid) + "." + flat;
}

ParamService::ParamService(std::string full_node_name, const Parameters* params)
    : node_(std::move(full_node_name)), params_(params) {
  std::error_code ec;
  fs::create_directories(ParamsDir(), ec);
  stem_ = ParamsDir() + "/" + ParamsStem(::getpid(), node_);
}

ParamService::~ParamService() {
  for (const char* ext : {".yaml", ".set", ".result"}) std::remove((stem_ + ext).c_str());
}

void ParamService::Publish() {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "node" << YAML::Value << node_ << YAML::Key << "pid"
      << YAML::Value << static_cast<int>(::getpid()) << YAML::Key << "parameters" << YAML::Value
      << YAML::BeginMap;
  for (const auto& [name, info] : params_->Declared()) {
    auto ch = changed_.find(name);
    out << YAML::Key << name << YAML::Value << YAML::BeginMap << YAML::Key << "type"
        << YAML::Value << info.type << YAML::Key << "value" << YAML::Value
        << (ch != changed_.end() ? ch->second : info.value_text) << YAML::Key << "default"
        << YAML::Value << info.default_text << YAML::Key << "dynamic" << YAML::Value
        << IsDynamic(name) << YAML::Key << "description" << YAML::Value << info.description
        << YAML::EndMap;
  }
  out << YAML::EndMap << YAML::EndMap;
  WriteAtomically(stem_ + ".yaml", std::string(out.c_str()) + "\n");
}

void ParamService::Poll() {
  const std::string request = stem_ + ".set";
  std::ifstream in(request);
  if (!in) return;
  std::stringstream text;
  text << in.rdbuf();
  in.close();
  std::remove(request.c_str());
  std::string result = "ok";
  try {
    const YAML::Node req = YAML::Load(text.str());
    const std::string name = req["name"].as<std::string>();
    const auto& declared = params_->Declared();
    if (declared.count(name) == 0) {
      std::string names;
      for (const auto& kv : declared) names += " " + kv.first;
      result = "error: node " + node_ + " has no parameter '" + name + "' (its parameters:" +
               names + ")";
    } else if (!IsDynamic(name)) {
      result = "error: parameter '" + name + "' of " + node_ +
               " is not dynamic (it is read at start-up only: restart the node with " + name +
               ":=VALUE)";
    } else {
      setters_.at(name)(req["value"]);
      changed_[name] = util::YamlFlow(req["value"]);
      Publish();
    }
  } catch (const std::exception& e) {
    result = std::string("error: ") + e.what();
  }
  WriteAtomically(stem_ + ".result", result + "\n");
}

}  // namespace p2i::runtime
