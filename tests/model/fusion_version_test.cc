/// @file fusion_version_test.cc
/// @brief Fusion version folders: round trip, refusal of incomplete folders, listing and pruning,
/// and a writer killed mid-write leaving the previous version loadable.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "model/fusion_version.h"
#include "tests/model/model_test_util.h"

using namespace p2i::model;
namespace fs = std::filesystem;

namespace {

FusionVersionManifest Manifest(uint64_t v, const std::string& keyframes) {
  FusionVersionManifest m;
  m.version = v;
  m.step = 10 * static_cast<int64_t>(v);
  m.frames_integrated = 5 * v;
  m.keyframes_dir = keyframes;
  m.keyframe_count = v;
  m.width = 32;
  m.height = 24;
  m.voxel_size_m = 0.02;
  m.block_resolution = 8;
  m.trunc_voxels = 3.0;
  return m;
}

void Payload(const std::string& dir) {
  std::ofstream(dir + "/tsdf.npz") << "tsdf";
  std::ofstream(dir + "/refine.pt") << "weights";
}

}  // namespace

TEST_CASE("A fusion version folder round-trips and refuses incomplete folders", "[unit]") {
  const std::string root = testing::TempDir("fusion_version");
  fs::create_directories(root + "/keyframes");
  const std::string versions = root + "/versions";
  fs::create_directories(versions);
  const std::string dir = FusionVersionDir(versions, 3);
  CHECK(fs::path(dir).filename() == "fusion_v000003");
  WriteFusionVersion(dir, Manifest(3, root + "/keyframes"), Payload);
  const FusionVersionManifest m = ReadFusionVersion(dir);
  CHECK(m.version == 3);
  CHECK(m.step == 30);
  CHECK(m.keyframe_count == 3);
  CHECK(m.width == 32);
  CHECK(m.height == 24);
  CHECK(m.block_resolution == 8);
  CHECK(m.trunc_voxels == 3.0);
  CHECK_THROWS_WITH(WriteFusionVersion(dir, Manifest(3, ""), Payload),
                    Catch::Contains("never rewritten"));

  // A payload that throws leaves nothing behind.
  const std::string bad = FusionVersionDir(versions, 4);
  CHECK_THROWS_WITH(WriteFusionVersion(bad, Manifest(4, ""),
                                       [](const std::string&) { throw std::runtime_error("disk"); }),
                    Catch::Contains("disk"));
  CHECK_FALSE(fs::exists(bad));
  CHECK(ListFusionVersions(versions) == std::vector<uint64_t>{3});

  fs::remove(dir + "/tsdf.npz");
  CHECK_THROWS_WITH(ReadFusionVersion(dir), Catch::Contains("tsdf.npz"));
  CHECK_THROWS_WITH(ReadFusionVersion(root), Catch::Contains("manifest.json"));
  fs::remove_all(root);
}

TEST_CASE("A writer killed mid-write leaves the previous version loadable", "[unit]") {
  const std::string root = testing::TempDir("fusion_version_kill");
  fs::create_directories(root + "/keyframes");
  const std::string versions = root + "/versions";
  fs::create_directories(versions);
  WriteFusionVersion(FusionVersionDir(versions, 1), Manifest(1, root + "/keyframes"), Payload);

  int fds[2];
  REQUIRE(::pipe(fds) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::close(fds[0]);
    try {
      WriteFusionVersion(FusionVersionDir(versions, 2), Manifest(2, root + "/keyframes"),
                         [&](const std::string& dir) {
                           std::ofstream(dir + "/tsdf.npz") << "half a tsdf";
                           const char c = 'x';
                           (void)!::write(fds[1], &c, 1);  // payload half written
                           for (;;) ::pause();               // killed here
                         });
    } catch (...) {
    }
    ::_exit(0);
  }
  ::close(fds[1]);
  char c = 0;
  REQUIRE(::read(fds[0], &c, 1) == 1);
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(fds[0]);

  CHECK(ListFusionVersions(versions) == std::vector<uint64_t>{1});  // the temp folder is no version
  CHECK(ReadFusionVersion(FusionVersionDir(versions, 1)).version == 1);
  CHECK_THROWS(ReadFusionVersion(FusionVersionDir(versions, 2)));
  // The next start cleans the temp folder up and keeps the newest versions.
  WriteFusionVersion(FusionVersionDir(versions, 2), Manifest(2, root + "/keyframes"), Payload);
  WriteFusionVersion(FusionVersionDir(versions, 3), Manifest(3, root + "/keyframes"), Payload);
  CHECK(PruneFusionVersions(versions, 2) == 2);  // the killed writer's temp + version 1
  CHECK(ListFusionVersions(versions) == std::vector<uint64_t>({2, 3}));
  for (const auto& e : fs::directory_iterator(versions))
    CHECK(e.path().filename().string().find(".tmp.") == std::string::npos);
  fs::remove_all(root);
}

TEST_CASE("Pruning keeps versions younger than the minimum age, beyond keep", "[unit]") {
  const std::string root = testing::TempDir("fusion_version_age");
  const std::string versions = root + "/versions";
  for (uint64_t v = 1; v <= 3; ++v)
    WriteFusionVersion(FusionVersionDir(versions, v), Manifest(v, root + "/keyframes"), Payload);
  // Just written: a reader told of version 1 a moment ago still finds it.
  CHECK(PruneFusionVersions(versions, 1, 3600.0) == 0);
  CHECK(ListFusionVersions(versions) == std::vector<uint64_t>({1, 2, 3}));
  // Version 1 an hour old: it goes; 2 is young and stays although keep is 1.
  fs::last_write_time(FusionVersionDir(versions, 1),
                      fs::file_time_type::clock::now() - std::chrono::hours(1));
  CHECK(PruneFusionVersions(versions, 1, 3600.0 - 60.0) == 1);
  CHECK(ListFusionVersions(versions) == std::vector<uint64_t>({2, 3}));
  // No minimum age: only the newest is kept.
  CHECK(PruneFusionVersions(versions, 1) == 1);
  CHECK(ListFusionVersions(versions) == std::vector<uint64_t>{3});
  fs::remove_all(root);
}
