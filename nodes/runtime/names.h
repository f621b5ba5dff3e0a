/// @file names.h
/// @brief Topic/service name resolution (ROS style: absolute, relative, private ~) and remapping.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace p2i::runtime {

/// Resolves and remaps names for one node.
///
/// "/a/b" is absolute; "a/b" resolves under the namespace ("/ns/a/b"); "~/a" or "~a" resolves
/// under the node ("/ns/node/a"). Remap rules FROM:=TO are resolved the same way and compared
/// after resolution, so `-r pose:=/robot/pose` affects a node that uses "pose" in namespace "/".
/// Names may contain [A-Za-z0-9_/] (and a leading ~); anything else throws StartupError.
/// Thread-compatible (immutable after construction).
class NameResolver {
 public:
  NameResolver(std::string node_namespace, std::string node_name,
               const std::vector<std::pair<std::string, std::string>>& remaps = {});

  /// Resolved, remapped absolute name.
  std::string Resolve(const std::string& name) const;
  /// Resolved without remapping.
  std::string ResolveNoRemap(const std::string& name) const;

  const std::string& Namespace() const { return namespace_; }
  const std::string& NodeName() const { return node_name_; }
  /// "/ns/name".
  std::string FullNodeName() const;

 private:
  std::string namespace_;
  std::string node_name_;
  std::map<std::string, std::string> remaps_;
};

/// Normalises a namespace: leading '/', no trailing '/' (except the root "/").
std::string NormalizeNamespace(const std::string& ns);

}  // namespace p2i::runtime
