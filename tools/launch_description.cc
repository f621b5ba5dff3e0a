/// @file launch_description.cc
/// @brief Reading launch YAML (args, let, include, group, node) into a LaunchDescription.
#include "tools/launch_description.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "tools/launch_substitution.h"
#include "util/yaml_flow.h"

namespace p2i::tools {
namespace {

namespace fs = std::filesystem;

// Deep enough for real launch trees, shallow enough to report an include cycle quickly.
constexpr int kMaxIncludeDepth = 16;

std::string Where(const std::string& file, const YAML::Node& node) {
  const int line = node.Mark().is_null() ? 0 : node.Mark().line + 1;
  return file + ":" + std::to_string(line);
}

[[noreturn]] void Fail(const std::string& file, const YAML::Node& node, const std::string& key,
                       const std::string& what) {
  throw LaunchError(Where(file, node) + ": " + (key.empty() ? "" : "key '" + key + "': ") + what);
}

// yaml-cpp keeps both entries of a duplicated key and `node[key]` returns one of them: the
// other value would be silently ignored. Refuse it, naming both lines.
void CheckDuplicateKeys(const std::string& file, const YAML::Node& node) {
  if (node.IsMap()) {
    std::map<std::string, YAML::Node> seen;
    for (const auto& kv : node) {
      if (kv.first.IsScalar()) {
        const std::string key = kv.first.Scalar();
        auto it = seen.find(key);
        if (it != seen.end()) {
          Fail(file, kv.first, key, "duplicate key (first at line " +
                                        std::to_string(it->second.Mark().line + 1) +
                                        "); remove one of them");
        }
        seen.emplace(key, kv.first);
      }
      CheckDuplicateKeys(file, kv.second);
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) CheckDuplicateKeys(file, item);
  }
}

std::string Join(const std::set<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

bool IsIdentifier(const std::string& s, bool allow_dot = false) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || (allow_dot && c == '.'))) {
      return false;
    }
  }
  return true;
}

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw LaunchError(path + ": cannot open launch file (check the path)");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string AbsolutePath(const std::string& path) {
  return fs::absolute(fs::path(path)).lexically_normal().string();
}

std::string Dirname(const std::string& path) { return fs::path(path).parent_path().string(); }

/// Reads one launch tree. Holds the result while reading; not reusable.
class Reader {
 public:
  explicit Reader(const std::map<std::string, std::string>& overrides) : overrides_(overrides) {}

  LaunchDescription ReadTop(const std::string& text, const std::string& path) {
    SubstitutionScope scope;
    scope.vars = overrides_;
    scope.file = AbsolutePath(path);
    std::string ns = "/";
    ReadText(text, scope, &ns, 0, "");
    for (const auto& [name, value] : overrides_) {
      if (declared_.count(name) == 0) {
        throw LaunchError(scope.file + ": command-line argument '" + name + ":=" + value +
                          "' is not declared by any `arg` (declared: " +
                          (declared_.empty() ? std::string("none") : Join(declared_)) +
                          "; see `p2i launch " + path + " --show-args`)");
      }
    }
    CheckMachines();
    out_.top_level_vars = top_vars_;
    return std::move(out_);
  }

 private:
  void ReadText(const std::string& text, SubstitutionScope& scope, std::string* ns, int depth,
                const std::string& include_site) {
    const std::string& file = scope.file;
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw LaunchError(file + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " +
                        e.msg);
    }
    CheckDuplicateKeys(file, root);
    if (!root.IsMap() || !root["launch"]) {
      Fail(file, root, "launch", "a launch file is a map with one key `launch:` holding a list");
    }
    for (const auto& kv : root) {
      const std::string key = kv.first.as<std::string>();
      if (key != "launch") Fail(file, kv.first, key, "unknown top-level key (only `launch:`)");
    }
    const YAML::Node list = root["launch"];
    if (!list.IsSequence()) Fail(file, list, "launch", "must be a list of entities");
    ReadEntities(list, scope, ns, depth, include_site);
    if (depth == 0) top_vars_ = scope.vars;
  }

  void ReadEntities(const YAML::Node& list, SubstitutionScope& scope, std::string* ns, int depth,
                    const std::string& include_site) {
    const std::string& file = scope.file;
    for (const auto& item : list) {
      if (!item.IsMap() || item.size() != 1) {
        Fail(file, item, "",
             "each launch entity is a map with exactly one key (arg, let, include, group, node, "
             "push-ros-namespace)");
      }
      const auto kv = *item.begin();
      const std::string kind = kv.first.as<std::string>();
      const YAML::Node body = kv.second;
      if (kind == "arg") {
        ReadArg(body, scope, depth, include_site);
      } else if (kind == "let") {
        CheckKeys(body, file, "let", {"name", "value"});
        const std::string name = Required(body, "name", file, "let");
        if (!IsIdentifier(name)) Fail(file, body["name"], "name", "'" + name + "' is no name");
        scope.vars[name] = Text(body, "value", scope, "let", true);
      } else if (kind == "include") {
        ReadInclude(body, scope, *ns, depth);
      } else if (kind == "group") {
        ReadGroup(body, scope, *ns, depth, include_site);
      } else if (kind == "push-ros-namespace" || kind == "push_ros_namespace") {
        CheckKeys(body, file, kind, {"namespace"});
        *ns = Namespace(body, "namespace", scope, *ns, kind);
      } else if (kind == "node") {
        ReadNode(body, kv.first, scope, *ns);
      } else if (kind == "machine") {
        ReadMachine(body, kv.first, scope);
      } else {
        Fail(file, kv.first, kind,
             "unknown launch entity (supported: arg, let, include, group, node, "
             "machine, push-ros-namespace)");
      }
    }
  }

  void ReadArg(const YAML::Node& body, SubstitutionScope& scope, int depth,
               const std::string& include_site) {
    const std::string& file = scope.file;
    CheckKeys(body, file, "arg", {"name", "default", "description"});
    LaunchArgument arg;
    arg.name = Required(body, "name", file, "arg");
    if (!IsIdentifier(arg.name)) {
      Fail(file, body["name"], "name", "'" + arg.name + "' is not a valid argument name");
    }
    arg.source = Where(file, body);
    if (body["description"]) arg.description = Required(body, "description", file, "arg");
    if (body["default"]) {
      arg.has_default = true;
      arg.default_value = Text(body, "default", scope, "arg", true);
    }
    declared_.insert(arg.name);
    out_.arguments.push_back(arg);
    if (scope.vars.count(arg.name) != 0) return;  // given on the command line or by the include
    if (!arg.has_default) {
      const std::string how =
          depth == 0 ? "pass it on the command line: p2i launch " + file + " " + arg.name +
                           ":=VALUE"
                     : "add `- {name: " + arg.name + ", value: ...}` to the `arg:` list of the "
                       "include at " + include_site + ", or pass " + arg.name +
                       ":=VALUE on the command line";
      Fail(file, body, "name",
           "launch argument '" + arg.name + "' has no default and was not given; " + how);
    }
    scope.vars[arg.name] = arg.default_value;
  }

  void ReadInclude(const YAML::Node& body, const SubstitutionScope& scope, const std::string& ns,
                   int depth) {
    const std::string& file = scope.file;
    CheckKeys(body, file, "include", {"file", "arg"});
    std::string path = Text(body, "file", scope, "include", true);
    if (fs::path(path).is_relative()) path = (fs::path(Dirname(file)) / path).string();
    path = AbsolutePath(path);
    if (!fs::is_regular_file(path)) {
      Fail(file, body["file"], "file", "included launch file '" + path + "' does not exist");
    }
    if (depth + 1 > kMaxIncludeDepth) {
      Fail(file, body, "include",
           "includes nest deeper than " + std::to_string(kMaxIncludeDepth) +
               " levels (an include cycle?)");
    }
    SubstitutionScope child;
    child.vars = scope.vars;
    child.file = path;
    if (body["arg"]) {
      const YAML::Node args = body["arg"];
      if (!args.IsSequence()) Fail(file, args, "arg", "must be a list of {name, value}");
      for (const auto& a : args) {
        CheckKeys(a, file, "include arg", {"name", "value"});
        const std::string name = Required(a, "name", file, "include arg");
        child.vars[name] = Text(a, "value", scope, "include arg", true);
      }
    }
    std::string child_ns = ns;
    ReadText(ReadWholeFile(path), child, &child_ns, depth + 1, Where(file, body));
  }

  void ReadGroup(const YAML::Node& body, const SubstitutionScope& scope, const std::string& ns,
                 int depth, const std::string& include_site) {
    const std::string& file = scope.file;
    SubstitutionScope child = scope;  // a group is scoped: its `let`s do not leak out
    std::string child_ns = ns;
    YAML::Node children;
    if (body.IsSequence()) {
      children = body;
    } else if (body.IsMap()) {
      CheckKeys(body, file, "group", {"namespace", "children", "launch"});
      if (body["namespace"]) child_ns = Namespace(body, "namespace", scope, ns, "group");
      if (static_cast<bool>(body["children"]) == static_cast<bool>(body["launch"])) {
        Fail(file, body, "children", "a group needs exactly one list `children:` (or `launch:`)");
      }
      children = body["children"] ? body["children"] : body["launch"];
      if (!children.IsSequence()) Fail(file, children, "children", "must be a list of entities");
    } else {
      Fail(file, body, "group", "must be a list of entities or {namespace, children}");
    }
    ReadEntities(children, child, &child_ns, depth, include_site);
  }

  void ReadNode(const YAML::Node& body, const YAML::Node& key, const SubstitutionScope& scope,
                const std::string& ns) {
    const std::string& file = scope.file;
    CheckKeys(body, file, "node",
              {"pkg", "exec", "name", "namespace", "param", "remap", "args", "respawn",
               "respawn_delay", "output", "required", "machine"});
    NodeDescription node;
    node.source = Where(file, key);  // the `node:` line
    if (body["pkg"]) node.pkg = Text(body, "pkg", scope, "node", true);
    node.exec = Text(body, "exec", scope, "node", true);
    if (node.exec.empty() || node.exec.find_first_of("/ \t") != std::string::npos) {
      Fail(file, body["exec"], "exec",
           "'" + node.exec + "' must be an executable name such as camera (runs p2i_camera)");
    }
    if (body["name"]) {
      node.name = Text(body, "name", scope, "node", true);
      if (!IsIdentifier(node.name)) {
        Fail(file, body["name"], "name",
             "'" + node.name + "' is not a node name (letters, digits, _; no '/')");
      }
    }
    node.node_namespace = body["namespace"] ? Namespace(body, "namespace", scope, ns, "node") : ns;
    if (body["param"]) ReadParams(body["param"], scope, &node);
    if (body["remap"]) ReadRemaps(body["remap"], scope, &node);
    ReadProcessOptions(body, scope, &node);
    const std::string full = JoinNamespace(node.node_namespace, node.DisplayName());
    const auto [it, inserted] = node_sources_.emplace(full, node.source);
    if (!inserted) {
      Fail(file, body, "name",
           "a second node named " + full + " (the first is at " + it->second +
               "); give each node a distinct `name:` or `namespace:`");
    }
    out_.nodes.push_back(std::move(node));
  }

  // A node's `param:` list: {name, value} entries and {from: FILE} parameter files.
  void ReadParams(const YAML::Node& params, const SubstitutionScope& scope, NodeDescription* node) {
    const std::string& file = scope.file;
    if (!params.IsSequence()) {
      Fail(file, params, "param", "must be a list of {name, value} or {from: FILE}");
    }
    for (const auto& p : params) {
      LaunchParam param;
      param.source = Where(file, p);
      if (p.IsMap() && p["from"]) {
        CheckKeys(p, file, "param", {"from"});
        std::string path = Text(p, "from", scope, "param", true);
        if (fs::path(path).is_relative()) path = (fs::path(Dirname(file)) / path).string();
        param.from_file = AbsolutePath(path);
        if (!fs::is_regular_file(param.from_file)) {
          Fail(file, p["from"], "from", "parameter file '" + param.from_file + "' does not exist");
        }
      } else {
        CheckKeys(p, file, "param", {"name", "value"});
        param.name = Text(p, "name", scope, "param", true);
        if (!IsIdentifier(param.name, true)) {
          Fail(file, p["name"], "name", "'" + param.name + "' is not a parameter name");
        }
        if (!p["value"]) Fail(file, p, "value", "parameter '" + param.name + "' has no value");
        param.value_yaml = util::YamlFlow(SubstituteNode(p["value"], scope, "value"));
      }
      node->params.push_back(std::move(param));
    }
  }

  void ReadRemaps(const YAML::Node& remaps, const SubstitutionScope& scope, NodeDescription* node) {
    const std::string& file = scope.file;
    if (!remaps.IsSequence()) Fail(file, remaps, "remap", "must be a list of {from, to}");
    for (const auto& r : remaps) {
      CheckKeys(r, file, "remap", {"from", "to"});
      const std::string from = Text(r, "from", scope, "remap", false);
      const std::string to = Text(r, "to", scope, "remap", false);
      node->remaps.emplace_back(from, to);
    }
  }

  // How the node's process runs: args, machine, respawn (+ delay), required, output.
  void ReadProcessOptions(const YAML::Node& body, const SubstitutionScope& scope,
                          NodeDescription* node) {
    const std::string& file = scope.file;
    if (body["args"]) {
      const std::string args = Text(body, "args", scope, "node", true);
      try {
        node->args = SplitShellWords(args);
      } catch (const std::invalid_argument& e) {
        Fail(file, body["args"], "args", e.what());
      }
    }
    if (body["machine"]) node->machine = Text(body, "machine", scope, "node", false);
    if (body["respawn"]) node->respawn = Bool(body, "respawn", scope);
    if (body["required"]) node->required = Bool(body, "required", scope);
    if (body["respawn_delay"]) {
      const std::string text = Text(body, "respawn_delay", scope, "node", false);
      char* end = nullptr;
      node->respawn_delay = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !std::isfinite(node->respawn_delay) ||
          node->respawn_delay < 0) {
        Fail(file, body["respawn_delay"], "respawn_delay",
             "'" + text + "' must be a number of seconds >= 0");
      }
    }
    if (body["output"]) {
      node->output = Text(body, "output", scope, "node", false);
      if (node->output != "screen" && node->output != "log" && node->output != "both") {
        Fail(file, body["output"], "output", "'" + node->output + "' must be screen, log or both");
      }
    }
    if (node->respawn && node->required) {
      Fail(file, body, "required",
           "a node cannot be both `respawn` and `required` (required stops the launch when it "
           "exits; respawn restarts it)");
    }
  }

  void ReadMachine(const YAML::Node& body, const YAML::Node& key, const SubstitutionScope& scope) {
    const std::string& file = scope.file;
    CheckKeys(body, file, "machine", {"name", "address", "discovery_port"});
    MachineDescription m;
    m.source = Where(file, key);
    m.name = Text(body, "name", scope, "machine", false);
    if (!IsIdentifier(m.name)) Fail(file, body["name"], "name", "'" + m.name + "' is no name");
    m.address = Text(body, "address", scope, "machine", false);
    if (m.address.find_first_of(" /:\t") != std::string::npos)
      Fail(file, body["address"], "address", "'" + m.address + "' must be a host address such "
           "as 10.0.0.2 (no scheme, no port: the port is discovery_port)");
    if (body["discovery_port"]) {
      const std::string t = Text(body, "discovery_port", scope, "machine", false);
      char* end = nullptr;
      const long port = std::strtol(t.c_str(), &end, 10);
      if (end == t.c_str() || *end != '\0' || port < 1 || port > 65535)
        Fail(file, body["discovery_port"], "discovery_port", "'" + t + "' must be a port 1-65535");
      m.discovery_port = static_cast<int>(port);
    }
    for (const auto& other : out_.machines)
      if (other.name == m.name)
        Fail(file, body["name"], "name", "a second machine '" + m.name + "' (the first is at " +
             other.source + ")");
    out_.machines.push_back(m);
  }

  void CheckMachines() const {
    std::set<std::string> names;
    for (const auto& m : out_.machines) names.insert(m.name);
    for (const auto& n : out_.nodes) {
      if (n.machine.empty() && !names.empty())
        throw LaunchError(n.source + ": node '" + n.DisplayName() + "' names no `machine:` but "
                          "the launch file declares machines (" + Join(names) + "); give it one");
      if (!n.machine.empty() && names.count(n.machine) == 0)
        throw LaunchError(n.source + ": node '" + n.DisplayName() + "': machine '" + n.machine +
                          "' is not declared (declared: " +
                          (names.empty() ? std::string("none") : Join(names)) +
                          "; add `- machine: {name: " + n.machine + ", address: ...}`)");
    }
  }

  // --- small helpers -------------------------------------------------------------------------

  static void CheckKeys(const YAML::Node& map, const std::string& file, const std::string& what,
                        const std::set<std::string>& allowed) {
    if (!map.IsMap()) Fail(file, map, "", what + " must be a map of " + Join(allowed));
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>();
      if (allowed.count(key) == 0) {
        Fail(file, kv.first, key, "unknown key in " + what + " (allowed: " + Join(allowed) + ")");
      }
    }
  }

  static std::string Required(const YAML::Node& map, const char* key, const std::string& file,
                              const std::string& what) {
    const YAML::Node v = map[key];
    if (!v) Fail(file, map, key, "missing in " + what);
    if (!v.IsScalar()) Fail(file, v, key, "must be a string");
    return v.Scalar();
  }

  std::string Text(const YAML::Node& map, const char* key, const SubstitutionScope& scope,
                   const std::string& what, bool allow_empty) const {
    const YAML::Node v = map[key];
    const std::string raw = Required(map, key, scope.file, what);
    std::string text;
    try {
      text = Substitute(raw, scope);
    } catch (const std::invalid_argument& e) {
      Fail(scope.file, v, key, e.what());
    }
    if (!allow_empty && text.empty()) Fail(scope.file, v, key, "must not be empty");
    return text;
  }

  YAML::Node SubstituteNode(const YAML::Node& in, const SubstitutionScope& scope,
                            const std::string& key) const {
    if (in.IsScalar()) {
      try {
        return YAML::Node(Substitute(in.Scalar(), scope));
      } catch (const std::invalid_argument& e) {
        Fail(scope.file, in, key, e.what());
      }
    }
    if (in.IsSequence()) {
      YAML::Node out(YAML::NodeType::Sequence);
      for (const auto& v : in) out.push_back(SubstituteNode(v, scope, key));
      return out;
    }
    if (in.IsMap()) {
      YAML::Node out(YAML::NodeType::Map);
      for (const auto& kv : in) out[kv.first.Scalar()] = SubstituteNode(kv.second, scope, key);
      return out;
    }
    Fail(scope.file, in, key, "has no value");
  }

  bool Bool(const YAML::Node& map, const char* key, const SubstitutionScope& scope) const {
    const std::string t = Text(map, key, scope, "node", false);
    if (t == "true" || t == "True" || t == "TRUE" || t == "1") return true;
    if (t == "false" || t == "False" || t == "FALSE" || t == "0") return false;
    Fail(scope.file, map[key], key, "'" + t + "' must be true or false");
  }

  std::string Namespace(const YAML::Node& map, const char* key, const SubstitutionScope& scope,
                        const std::string& base, const std::string& what) const {
    const std::string ns = Text(map, key, scope, what, true);
    for (char c : ns) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/')) {
        Fail(scope.file, map[key], key,
             "'" + ns + "' is not a namespace (letters, digits, _ and /)");
      }
    }
    return JoinNamespace(base, ns);
  }

  std::map<std::string, std::string> overrides_;
  std::set<std::string> declared_;
  std::map<std::string, std::string> node_sources_;  // full node name -> FILE:LINE
  std::map<std::string, std::string> top_vars_;
  LaunchDescription out_;
};

}  // namespace

LaunchDescription LaunchDescriptionReader::ReadFile(
    const std::string& path, const std::map<std::string, std::string>& overrides) {
  return ReadString(ReadWholeFile(path), path, overrides);
}

LaunchDescription LaunchDescriptionReader::ReadString(
    const std::string& text, const std::string& path,
    const std::map<std::string, std::string>& overrides) {
  return Reader(overrides).ReadTop(text, path);
}

std::vector<LaunchArgument> LaunchDescriptionReader::ListArguments(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(ReadWholeFile(path));
  } catch (const YAML::Exception& e) {
    throw LaunchError(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " +
                      e.msg);
  }
  std::vector<LaunchArgument> out;
  if (!root.IsMap() || !root["launch"].IsSequence()) return out;
  for (const auto& item : root["launch"]) {
    if (!item.IsMap() || !item["arg"] || !item["arg"].IsMap()) continue;
    const YAML::Node a = item["arg"];
    LaunchArgument arg;
    if (a["name"] && a["name"].IsScalar()) arg.name = a["name"].Scalar();
    if (a["default"] && a["default"].IsScalar()) {
      arg.has_default = true;
      arg.default_value = a["default"].Scalar();
    }
    if (a["description"] && a["description"].IsScalar()) arg.description = a["description"].Scalar();
    arg.source = Where(path, a);
    out.push_back(arg);
  }
  return out;
}

std::map<std::string, std::string> ParseLaunchOverrides(const std::vector<std::string>& words) {
  std::map<std::string, std::string> out;
  for (const auto& w : words) {
    const auto pos = w.find(":=");
    if (pos == std::string::npos || pos == 0) {
      throw LaunchError("command line: '" + w + "' is not a launch argument; write name:=value");
    }
    out[w.substr(0, pos)] = w.substr(pos + 2);
  }
  return out;
}

std::vector<std::string> SplitShellWords(const std::string& text) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ' || c == '\t' || c == '\n') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else if (c == '\'' || c == '"') {
      const size_t end = text.find(c, i + 1);
      if (end == std::string::npos) {
        throw std::invalid_argument("unterminated " + std::string(1, c) + " quote in '" + text +
                                    "'");
      }
      word += text.substr(i + 1, end - i - 1);
      in_word = true;
      i = end;
    } else if (c == '\\' && i + 1 < text.size()) {
      word += text[++i];
      in_word = true;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

std::string JoinNamespace(const std::string& base, const std::string& ns) {
  const std::string joined = ns.empty() ? base : (ns[0] == '/' ? ns : base + "/" + ns);
  std::string out;
  std::istringstream in(joined);
  std::string part;
  while (std::getline(in, part, '/')) {
    if (!part.empty()) out += "/" + part;
  }
  return out.empty() ? "/" : out;
}

}  // namespace p2i::tools
