/// @file names.cc
/// @brief Name resolution and remapping.
#include "nodes/runtime/names.h"

#include <cctype>

#include "nodes/runtime/node_args.h"

namespace p2i::runtime {
namespace {

void CheckChars(const std::string& name) {
  if (name.empty()) throw StartupError("empty topic/service name");
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/' ||
                    (c == '~' && i == 0);
    if (!ok) {
      throw StartupError("name '" + name + "': character '" + std::string(1, c) +
                         "' not allowed (use letters, digits, '_' and '/')");
    }
  }
  if (name.find("//") != std::string::npos) {
    throw StartupError("name '" + name + "': empty path component ('//')");
  }
}

std::string Join(const std::string& base, const std::string& rest) {
  if (rest.empty()) return base;
  return base == "/" ? "/" + rest : base + "/" + rest;
}

}  // namespace

std::string NormalizeNamespace(const std::string& ns) {
  std::string out = ns.empty() || ns[0] != '/' ? "/" + ns : ns;
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  if (out != "/") CheckChars(out);
  return out;
}

NameResolver::NameResolver(std::string node_namespace, std::string node_name,
                           const std::vector<std::pair<std::string, std::string>>& remaps)
    : namespace_(NormalizeNamespace(node_namespace)), node_name_(std::move(node_name)) {
  if (node_name_.empty() || node_name_.find('/') != std::string::npos) {
    throw StartupError("node name '" + node_name_ + "' must be non-empty and contain no '/'");
  }
  CheckChars(node_name_);
  for (const auto& [from, to] : remaps) {
    remaps_[ResolveNoRemap(from)] = ResolveNoRemap(to);
  }
}

std::string NameResolver::FullNodeName() const { return Join(namespace_, node_name_); }

std::string NameResolver::ResolveNoRemap(const std::string& name) const {
  CheckChars(name);
  std::string out;
  if (name[0] == '/') {
    out = name;
  } else if (name[0] == '~') {
    std::string rest = name.substr(1);
    if (!rest.empty() && rest[0] == '/') rest = rest.substr(1);
    out = Join(FullNodeName(), rest);
  } else {
    out = Join(namespace_, name);
  }
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  return out;
}

std::string NameResolver::Resolve(const std::string& name) const {
  const std::string resolved = ResolveNoRemap(name);
  auto it = remaps_.find(resolved);
  return it == remaps_.end() ? resolved : it->second;
}

}  // namespace p2i::runtime
