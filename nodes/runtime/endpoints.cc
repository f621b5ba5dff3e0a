/// @file endpoints.cc
/// @brief Run directory, default endpoints and the file-based discovery registry.
#include "nodes/runtime/endpoints.h"

#include <dirent.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace p2i::runtime {
namespace {

void MakeDirs(const std::string& path) {
  std::string cur;
  std::stringstream ss(path);
  std::string part;
  if (!path.empty() && path[0] == '/') cur = "";
  while (std::getline(ss, part, '/')) {
    if (part.empty()) continue;
    cur += "/" + part;
    mkdir(cur.c_str(), 0700);
  }
}

std::string Flatten(const std::string& name) {
  std::string s = name;
  while (!s.empty() && s[0] == '/') s.erase(0, 1);
  std::replace(s.begin(), s.end(), '/', '.');
  return s.empty() ? "root" : s;
}

}  // namespace

std::string RunDir() {
  const char* env = std::getenv("P2I_RUN_DIR");
  std::string dir = env && *env ? env : "/tmp/p2i-" + std::to_string(getuid());
  MakeDirs(dir);
  // ipc:// sockets are not encrypted: only the user may reach them (docs/SECURITY.md).
  struct stat st {};
  if (::stat(dir.c_str(), &st) == 0 && (st.st_mode & 077) != 0) {
    if (st.st_uid != ::getuid() || ::chmod(dir.c_str(), 0700) != 0) {
      throw std::runtime_error("run directory " + dir + " (P2I_RUN_DIR) is open to other users "
                               "and cannot be made 0700 (owner uid " + std::to_string(st.st_uid) +
                               "): point P2I_RUN_DIR at a directory of your own");
    }
  }
  return dir;
}

std::string DefaultEndpoint(const std::string& kind, const std::string& resolved_name) {
  const std::string dir = RunDir();
  std::string path = dir + "/" + kind + "." + Flatten(resolved_name) + ".ipc";
  if (path.size() > 100) {
    char hash[32];
    std::snprintf(hash, sizeof(hash), "%016zx", std::hash<std::string>{}(resolved_name));
    path = dir + "/" + kind + "." + hash + ".ipc";
  }
  return "ipc://" + path;
}

std::string Registry::Register(const RegistryEntry& e) {
  const std::string dir = RunDir() + "/registry";
  MakeDirs(dir);
  const std::string path =
      dir + "/" + std::to_string(getpid()) + "." + e.kind + "." + Flatten(e.name);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) return "";
    out << "kind " << e.kind << "\nname " << e.name << "\ntype " << e.type << "\nendpoint "
        << e.endpoint << "\nnode " << e.node << "\npid " << getpid() << "\n";
    if (!e.remote_endpoint.empty()) out << "remote " << e.remote_endpoint << "\n";
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) return "";
  return path;
}

void Registry::Unregister(const std::string& path) {
  if (!path.empty()) std::remove(path.c_str());
}

void Registry::CheckEndpointFree(const std::string& endpoint, const std::string& what) {
  if (endpoint.rfind("ipc://", 0) != 0) return;  // tcp: bind itself fails if the port is taken
  for (const auto& e : List()) {
    if (e.endpoint == endpoint) {
      throw std::runtime_error(what + ": endpoint " + endpoint + " is already bound by " +
                               e.kind + " '" + e.name + "' of node " + e.node + " (pid " +
                               std::to_string(e.pid) +
                               "); give one of them another name or endpoint");
    }
  }
}

std::vector<RegistryEntry> Registry::List() { return ListDir(RunDir()); }

std::vector<std::string> Registry::UserRunDirs() {
  const std::string base = "/tmp/p2i-" + std::to_string(getuid());
  std::vector<std::string> out = {base};
  if (DIR* d = opendir(base.c_str())) {
    while (dirent* ent = readdir(d)) {
      const std::string name = ent->d_name;
      struct stat st {};
      const std::string dir = base + "/" + name;
      if (name.rfind("launch-", 0) == 0 && ::stat((dir + "/registry").c_str(), &st) == 0)
        out.push_back(dir);
    }
    closedir(d);
  }
  std::sort(out.begin() + 1, out.end());
  return out;
}

std::vector<RegistryEntry> Registry::ListDir(const std::string& run_dir) {
  std::vector<RegistryEntry> out;
  const std::string dir = run_dir + "/registry";
  DIR* d = opendir(dir.c_str());
  if (!d) return out;
  while (dirent* ent = readdir(d)) {
    const std::string fname = ent->d_name;
    if (fname == "." || fname == ".." || fname.size() < 4 ||
        fname.compare(fname.size() - 4, 4, ".tmp") == 0) {
      continue;
    }
    const std::string path = dir + "/" + fname;
    std::ifstream in(path);
    RegistryEntry e;
    std::string key, value;
    while (in >> key && std::getline(in >> std::ws, value)) {
      if (key == "kind") e.kind = value;
      else if (key == "name") e.name = value;
      else if (key == "type") e.type = value;
      else if (key == "endpoint") e.endpoint = value;
      else if (key == "node") e.node = value;
      else if (key == "pid") e.pid = std::atoi(value.c_str());
      else if (key == "remote") e.remote_endpoint = value;
    }
    if (e.pid <= 0 || (kill(e.pid, 0) != 0 && errno == ESRCH)) {
      std::remove(path.c_str());  // its process is gone
      continue;
    }
    out.push_back(e);
  }
  closedir(d);
  std::sort(out.begin(), out.end(), [](const RegistryEntry& a, const RegistryEntry& b) {
    return std::tie(a.kind, a.name, a.node) < std::tie(b.kind, b.name, b.node);
  });
  return out;
}

}  // namespace p2i::runtime
