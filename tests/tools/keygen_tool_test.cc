/// @file keygen_tool_test.cc
/// @brief `p2i keygen` as a user runs it: a key pair whose halves belong together, an existing
/// NAME.key / NAME.pub kept unless --force (exit 2, the message names the file and the flag),
/// no half-written key or .tmp file when writing fails, --init completing a directory.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "nodes/runtime/curve_auth.h"
#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/skip.h"
#include "tests/temp_dir.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using p2i::runtime::ReadKeyFile;
using p2i::testing::ReadFile;

namespace {

std::string Keygen(const std::string& args, int* code) {
  return p2i::testing::RunCommand(p2i::testing::BinDir() + "/p2i keygen " + args + " 2>&1", code);
}

int Mode(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<int>(st.st_mode & 0777) : -1;
}

bool AnyTmp(const std::string& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().extension() == ".tmp") return true;
  return false;
}

}  // namespace

TEST_CASE("p2i keygen writes a pair, refuses to overwrite without --force", "[integration]") {
  if (!p2i::runtime::CurveAvailable()) P2I_SKIP("libzmq without CURVE: p2i keygen cannot work");
  p2i::testing::TempDir tmp("keygen");
  const std::string dir = tmp / "keys";
  int code = -1;
  const std::string made = Keygen("robot --dir " + dir, &code);
  INFO(made);
  REQUIRE(code == 0);
  const auto pair = ReadKeyFile(dir + "/robot.key");
  const auto pub = ReadKeyFile(dir + "/robot.pub");
  CHECK(pub.public_z85 == pair.public_z85);
  CHECK(pub.secret_z85.empty());
  CHECK_FALSE(pair.secret_z85.empty());
  CHECK(Mode(dir + "/robot.key") == 0600);
  CHECK_THAT(made, Catch::Contains(pair.public_z85));

  // Again without --force: usage error (2), the file and the flag named, nothing changed.
  const std::string key_before = ReadFile(dir + "/robot.key");
  const std::string pub_before = ReadFile(dir + "/robot.pub");
  const std::string refused = Keygen("robot --dir " + dir, &code);
  CHECK(code == 2);
  CHECK_THAT(refused, Catch::Contains(dir + "/robot.key") && Catch::Contains("--force"));
  CHECK(ReadFile(dir + "/robot.key") == key_before);
  CHECK(ReadFile(dir + "/robot.pub") == pub_before);

  // Only NAME.pub there (e.g. another host's public key copied in): kept as well.
  std::ofstream(dir + "/hostb.pub") << "public " << pair.public_z85 << "\n";
  const std::string pub_only = Keygen("hostb --dir " + dir, &code);
  CHECK(code == 2);
  CHECK_THAT(pub_only, Catch::Contains(dir + "/hostb.pub") && Catch::Contains("--force"));
  CHECK_FALSE(fs::exists(dir + "/hostb.key"));

  // --force: a new pair, both halves replaced and matching.
  CHECK(Keygen("robot --force --dir " + dir, &code).find("public key:") != std::string::npos);
  CHECK(code == 0);
  const auto fresh = ReadKeyFile(dir + "/robot.key");
  CHECK(fresh.public_z85 != pair.public_z85);
  CHECK(ReadKeyFile(dir + "/robot.pub").public_z85 == fresh.public_z85);

  // A NAME that is a path is refused (it would write outside --dir).
  CHECK_THAT(Keygen("../escape --dir " + dir, &code), Catch::Contains("base name"));
  CHECK(code == 2);
  CHECK_FALSE(fs::exists(tmp / "escape.key"));
  CHECK_FALSE(AnyTmp(tmp.path()));
}

TEST_CASE("p2i keygen leaves no half-written key when writing fails", "[integration]") {
  if (!p2i::runtime::CurveAvailable()) P2I_SKIP("libzmq without CURVE: p2i keygen cannot work");
  p2i::testing::TempDir tmp("keygen_fail");
  int code = -1;
  // NAME.key is a folder: the new key cannot replace it (works as root too, unlike chmod).
  fs::create_directories(tmp / "stuck.key");
  std::ofstream(tmp / "stuck.pub") << "old\n";
  const std::string out = Keygen("stuck --force --dir " + tmp.path(), &code);
  INFO(out);
  CHECK(code == 1);
  CHECK_THAT(out, Catch::Contains(tmp / "stuck.key"));
  CHECK(fs::is_directory(tmp / "stuck.key"));
  CHECK(ReadFile(tmp / "stuck.pub") == "old\n");  // the .pub still matches whatever was there
  CHECK_FALSE(AnyTmp(tmp.path()));
  // The library call alone: same guarantee.
  const auto k = p2i::runtime::GenerateCurveKeyPair();
  CHECK_THROWS_WITH(p2i::runtime::WriteKeyFile(tmp / "stuck.key", k, true),
                    Catch::Contains("cannot replace"));
  CHECK_FALSE(AnyTmp(tmp.path()));
}

TEST_CASE("p2i keygen --init keeps an existing key and completes the directory", "[integration]") {
  if (!p2i::runtime::CurveAvailable()) P2I_SKIP("libzmq without CURVE: p2i keygen cannot work");
  p2i::testing::TempDir tmp("keygen_init");
  const std::string dir = tmp / "curve";
  int code = -1;
  Keygen("--init " + dir, &code);
  REQUIRE(code == 0);
  const auto self = ReadKeyFile(dir + "/self.key");
  CHECK(ReadKeyFile(dir + "/self.pub").public_z85 == self.public_z85);
  CHECK(ReadFile(dir + "/authorized_keys").find(self.public_z85) != std::string::npos);
  CHECK(Mode(dir) == 0700);
  fs::remove(dir + "/self.pub");
  const std::string again = Keygen("--init " + dir, &code);
  INFO(again);
  CHECK(code == 0);
  CHECK_THAT(again, Catch::Contains("kept the existing key pair"));
  CHECK(ReadKeyFile(dir + "/self.key").public_z85 == self.public_z85);
  CHECK(ReadKeyFile(dir + "/self.pub").public_z85 == self.public_z85);
  // authorized_keys lists the key once, not once per --init.
  const std::string auth = ReadFile(dir + "/authorized_keys");
  CHECK(auth.find(self.public_z85) == auth.rfind(self.public_z85));
}
