/// @file cmd_keygen.cc
/// @brief `p2i keygen NAME [--dir DIR]` (a CURVE key pair) and `p2i keygen --init DIR` (a key
/// directory for $P2I_CURVE_DIR); see docs/SECURITY.md. An existing NAME.key or NAME.pub is
/// replaced only with --force (else exit 2, the usage rule of docs/RUNTIME.md); a key and its
/// .pub are written in full before either replaces a file.
#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "nodes/runtime/curve_auth.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

namespace fs = std::filesystem;
using runtime::CurveKeyPair;

bool FileHasKey(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line))
    if (line.find(key) != std::string::npos) return true;
  return false;
}

// Writes NAME.key and NAME.pub of `dir` for a fresh pair: both are written in full (and
// fsynced) before either replaces a file, and a failure leaves no .tmp behind.
void WritePair(const std::string& dir, const std::string& name, const CurveKeyPair& k) {
  const std::string key = dir + "/" + name + ".key", pub = dir + "/" + name + ".pub";
  runtime::WriteKeyFileTmp(key, k, true);
  try {
    runtime::WriteKeyFileTmp(pub, k, false);
    runtime::CommitKeyFile(key);
  } catch (...) {
    std::remove((key + ".tmp").c_str());
    std::remove((pub + ".tmp").c_str());
    throw;
  }
  runtime::CommitKeyFile(pub);
}

int Init(const std::string& dir) {
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace);
  const std::string self = dir + "/self.key";
  CurveKeyPair k;
  if (fs::exists(self)) {
    k = runtime::ReadKeyFile(self);
    std::printf("kept the existing key pair %s\n", self.c_str());
    if (!fs::exists(dir + "/self.pub")) {  // complete the directory: the public half
      runtime::WriteKeyFile(dir + "/self.pub", k, false);
      std::printf("wrote %s/self.pub from it\n", dir.c_str());
    }
  } else {
    k = runtime::GenerateCurveKeyPair();
    WritePair(dir, "self", k);
    std::printf("wrote %s (secret, 0600) and %s/self.pub\n", self.c_str(), dir.c_str());
  }
  const std::string auth = dir + "/authorized_keys";
  if (!FileHasKey(auth, k.public_z85)) {
    std::ofstream(auth, std::ios::app) << k.public_z85 << " self\n";
    std::printf("listed this key in %s (add other hosts' public keys there)\n", auth.c_str());
  }
  const std::string servers = dir + "/servers";
  if (!fs::exists(servers)) {
    std::ofstream(servers) << "# HOST PUBLIC-KEY of each server this host connects to (* = any)\n"
                           << "* " << k.public_z85 << "\n";
    std::printf("wrote %s ('* <this key>': every server is this host until you add lines)\n",
                servers.c_str());
  }
  std::printf("public key: %s\nuse it: export P2I_CURVE_DIR=%s\n", k.public_z85.c_str(),
              fs::absolute(dir).c_str());
  return 0;
}

int RunKeygen(const std::vector<std::string>& args) {
  CLI::App app{"Make ZeroMQ CURVE keys for p2i's tcp endpoints (docs/SECURITY.md).\n"
               "  p2i keygen NAME [--dir DIR]   writes DIR/NAME.key (key pair, 0600) and NAME.pub\n"
               "  p2i keygen --init DIR         a key directory for P2I_CURVE_DIR (self.key,\n"
               "                                authorized_keys, servers)",
               "p2i keygen"};
  std::string name, dir = ".", init;
  bool force = false;
  app.add_option("name", name, "Base name of the key files");
  app.add_option("--dir", dir, "Folder for NAME.key / NAME.pub (default: current folder)");
  app.add_option("--init", init, "Create or complete a key directory for P2I_CURVE_DIR");
  app.add_flag("--force", force, "Replace an existing NAME.key / NAME.pub (else exit 2, nothing "
                                 "written)");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  try {
    if (!init.empty()) return Init(init);
    if (name.empty()) {
      std::fprintf(stderr, "p2i keygen: give a NAME or --init DIR (see --help)\n");
      return 2;
    }
    if (name.find('/') != std::string::npos || name == "." || name == "..") {
      std::fprintf(stderr, "p2i keygen: NAME '%s' must be a base name, not a path (put the "
                           "folder in --dir)\n", name.c_str());
      return 2;
    }
    const std::string key = dir + "/" + name + ".key", pub = dir + "/" + name + ".pub";
    for (const std::string& path : {key, pub}) {
      if (!force && fs::exists(fs::symlink_status(path))) {
        // A usage matter (exit 2): the user asks for a new key where one is kept.
        std::fprintf(stderr, "p2i keygen: %s exists; nothing was written. Pass --force to "
                             "replace %s and %s (clients that know the old public key must "
                             "then be given the new one)\n",
                     path.c_str(), key.c_str(), pub.c_str());
        return 2;
      }
    }
    fs::create_directories(dir);
    const CurveKeyPair k = runtime::GenerateCurveKeyPair();
    WritePair(dir, name, k);
    std::printf("wrote %s (secret, 0600) and %s\npublic key: %s\n", key.c_str(), pub.c_str(),
                k.public_z85.c_str());
    return 0;
  } catch (const std::invalid_argument& e) {  // a bad option value: usage/config (exit 2)
    std::fprintf(stderr, "p2i keygen: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // an IO error: runtime (exit 1)
    std::fprintf(stderr, "p2i keygen: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace

P2I_COMMAND("keygen", "Make CURVE keys: keygen NAME | keygen --init DIR (docs/SECURITY.md)",
            RunKeygen);

}  // namespace p2i::tools
