/// @file param_service.h
/// @brief `p2i param list/get/set` on a running node, through its run dir (no daemon, like the
/// discovery registry): each node keeps `$P2I_RUN_DIR/params/<pid>.<node>.yaml` (its declared
/// parameters: type, value, default, description, dynamic) and checks every 0.25 s for a
/// `<pid>.<node>.set` request ({name, value}); it applies the value when the parameter is
/// declared dynamic (Node::DeclareDynamic), rewrites the .yaml and answers in
/// `<pid>.<node>.result` ("ok" or "error: ..."). Files are written atomically (tmp + rename).
#pragma once

#include <functional>
#include <map>
#include <string>

#include <yaml-cpp/yaml.h>

#include "nodes/runtime/parameters.h"

namespace p2i::runtime {

/// The folder of the parameter files: $P2I_RUN_DIR/params.
std::string ParamsDir();
/// The same folder of another run dir (`p2i param` reads those of DiscoveryRunDirs()).
std::string ParamsDir(const std::string& run_dir);
/// The file stem of a node: "<pid>.<full name with '/' -> '.'>".
std::string ParamsStem(int pid, const std::string& full_node_name);

/// Node side. Thread-compatible: used on the node's executor thread.
class ParamService {
 public:
  using Setter = std::function<void(const YAML::Node& value)>;  ///< throws on a bad value
  ParamService(std::string full_node_name, const Parameters* params);
  ~ParamService();  ///< removes the node's files
  void SetDynamic(const std::string& name, Setter setter) { setters_[name] = std::move(setter); }
  bool IsDynamic(const std::string& name) const { return setters_.count(name) > 0; }
  /// Writes the .yaml (call after every parameter is declared).
  void Publish();
  /// Handles a pending .set request, if any (the node's timer calls it).
  void Poll();
  /// Values changed through Poll(), by name (YAML flow text), for the .yaml.
  const std::map<std::string, std::string>& Changed() const { return changed_; }

 private:
  std::string node_;
  const Parameters* params_;
  std::string stem_;
  std::map<std::string, Setter> setters_;
  std::map<std::string, std::string> changed_;
};

}  // namespace p2i::runtime
