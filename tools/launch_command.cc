/// @file launch_command.cc
/// @brief Node command lines, executable lookup and inline parameter files.
#include "tools/launch_command.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace p2i::tools {
namespace {

namespace fs = std::filesystem;

bool IsExecutableFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

}  // namespace

NodeCommand BuildNodeCommand(const NodeDescription& node, const std::string& executable,
                             const std::string& params_dir, int index) {
  NodeCommand cmd;
  cmd.display_name = node.DisplayName();
  cmd.argv.push_back(executable);
  if (!node.name.empty()) {
    cmd.argv.push_back("--name");
    cmd.argv.push_back(node.name);
  }
  cmd.argv.push_back("--namespace");
  cmd.argv.push_back(node.node_namespace);
  std::string inline_text;
  const auto flush_inline = [&] {
    if (inline_text.empty()) return;
    const std::string path = (fs::path(params_dir) /
                              (std::to_string(index) + "_" + node.DisplayName() + "." +
                               std::to_string(cmd.param_files.size()) + ".yaml"))
                                 .string();
    cmd.param_files.emplace_back(path, inline_text);
    cmd.argv.push_back("--params-file");
    cmd.argv.push_back(path);
    inline_text.clear();
  };
  for (const auto& p : node.params) {
    if (p.IsFile()) {
      flush_inline();
      cmd.argv.push_back("--params-file");
      cmd.argv.push_back(p.from_file);
    } else {
      // "#@ FILE:LINE": the node names the launch file's line, not this temporary file, in
      // its parameter errors (Parameters::LoadFile).
      inline_text += p.name + ": " + p.value_yaml +
                     (p.source.empty() ? "" : "  #@ " + p.source) + "\n";
    }
  }
  flush_inline();
  for (const auto& [from, to] : node.remaps) {
    cmd.argv.push_back("-r");
    cmd.argv.push_back(from + ":=" + to);
  }
  cmd.argv.insert(cmd.argv.end(), node.args.begin(), node.args.end());
  return cmd;
}

std::string FindNodeExecutable(const std::string& exec, const std::string& self_dir,
                               std::string* searched) {
  std::vector<fs::path> candidates;
  if (!self_dir.empty()) candidates.push_back(fs::path(self_dir) / ("p2i_" + exec));
  const char* path_env = std::getenv("PATH");
  std::vector<std::string> path_dirs;
  if (path_env != nullptr) {
    std::istringstream in(path_env);
    std::string dir;
    while (std::getline(in, dir, ':')) {
      if (!dir.empty()) path_dirs.push_back(dir);
    }
  }
  for (const auto& d : path_dirs) candidates.push_back(fs::path(d) / ("p2i_" + exec));
  for (const auto& d : path_dirs) candidates.push_back(fs::path(d) / exec);
  for (const auto& c : candidates) {
    if (IsExecutableFile(c)) return c.string();
  }
  if (searched != nullptr) {
    *searched = "p2i_" + exec + " in " + (self_dir.empty() ? "(unknown)" : self_dir) +
                " (beside p2i), then p2i_" + exec + " and " + exec + " on $PATH";
  }
  return "";
}

std::string SelfDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

std::string ShellQuote(const std::string& word) {
  if (!word.empty() &&
      word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                             "_-./:=,@+%") == std::string::npos) {
    return word;
  }
  std::string out = "'";
  for (char c : word) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

void WriteParamFiles(const NodeCommand& command) {
  for (const auto& [path, text] : command.param_files) {
    fs::create_directories(fs::path(path).parent_path());
    std::ofstream out(path, std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("cannot write parameter file '" + path + "'");
  }
}

}  // namespace p2i::tools
