/// @file fusion_version.cc
/// @brief Version folders of the `fusion` method (see fusion_version.h).
#include "model/fusion_version.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace p2i::model {

namespace fs = std::filesystem;

namespace {

constexpr const char* kPrefix = "fusion_v";

void SyncPath(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// Committed version number of a folder name, or 0 when it is not one ("fusion_v000012").
uint64_t VersionOf(const std::string& name) {
  if (name.rfind(kPrefix, 0) != 0) return 0;
  const std::string digits = name.substr(std::char_traits<char>::length(kPrefix));
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return 0;
  return std::strtoull(digits.c_str(), nullptr, 10);
}

}  // namespace

std::string FusionVersionManifest::ToJson() const {
  nlohmann::json j;
  j["kind"] = "p2i_fusion_version";
  j["format_version"] = 1;
  j["version"] = version;
  j["step"] = step;
  j["frames_integrated"] = frames_integrated;
  j["tsdf_file"] = tsdf_file;
  j["refine_file"] = refine_file;
  j["keyframes_dir"] = keyframes_dir;
  j["keyframe_count"] = keyframe_count;
  j["width"] = width;
  j["height"] = height;
  j["voxel_size_m"] = voxel_size_m;
  j["block_resolution"] = block_resolution;
  j["trunc_voxels"] = trunc_voxels;
  if (!submap_files.empty()) {
    j["submap_files"] = submap_files;
    j["submap_frame_counts"] = submap_frame_counts;
    j["keyframe_submaps"] = keyframe_submaps;
    j["submap_frames"] = submap_frames;
  }
  j["val_psnr"] = val_psnr;
  j["val_psnr_blend"] = val_psnr_blend;
  return j.dump(2);
}

FusionVersionManifest FusionVersionManifest::FromJson(const std::string& text,
                                                      const std::string& source) {
  FusionVersionManifest m;
  try {
    const auto j = nlohmann::json::parse(text);
    if (j.value("kind", std::string()) != "p2i_fusion_version")
      throw std::runtime_error(source + ": not a fusion version manifest");
    if (j.at("format_version").get<int>() != 1)
      throw std::runtime_error(source + ": format version " +
                               std::to_string(j.at("format_version").get<int>()) +
                               " (this build reads 1): use the trainer of the same build");
    m.version = j.at("version").get<uint64_t>();
    m.step = j.at("step").get<int64_t>();
    m.frames_integrated = j.at("frames_integrated").get<uint64_t>();
    m.tsdf_file = j.at("tsdf_file").get<std::string>();
    m.refine_file = j.at("refine_file").get<std::string>();
    m.keyframes_dir = j.at("keyframes_dir").get<std::string>();
    m.keyframe_count = j.at("keyframe_count").get<uint64_t>();
    m.width = j.at("width").get<int>();
    m.height = j.at("height").get<int>();
    m.voxel_size_m = j.at("voxel_size_m").get<double>();
    m.block_resolution = j.value("block_resolution", m.block_resolution);
    m.trunc_voxels = j.value("trunc_voxels", m.trunc_voxels);
    if (j.contains("submap_files")) {
      m.submap_files = j.at("submap_files").get<std::vector<std::string>>();
      m.submap_frame_counts = j.at("submap_frame_counts").get<std::vector<int>>();
      m.keyframe_submaps = j.at("keyframe_submaps").get<std::vector<int>>();
      m.submap_frames = j.at("submap_frames").get<int>();
      if (m.submap_frame_counts.size() != m.submap_files.size() ||
          m.keyframe_submaps.size() != m.keyframe_count || m.submap_frames <= 0)
        throw std::runtime_error(source + ": inconsistent submaps (" +
                                 std::to_string(m.submap_files.size()) + " files, " +
                                 std::to_string(m.submap_frame_counts.size()) + " frame counts, " +
                                 std::to_string(m.keyframe_submaps.size()) + " keyframe submaps for " +
                                 std::to_string(m.keyframe_count) + " keyframes, submap_frames " +
                                 std::to_string(m.submap_frames) + ")");
      for (int s : m.keyframe_submaps)
        if (s < -1 || s >= static_cast<int>(m.submap_files.size()))
          throw std::runtime_error(source + ": keyframe submap " + std::to_string(s) +
                                   " names no submap file");
    }
    m.val_psnr = j.value("val_psnr", 0.0);
    m.val_psnr_blend = j.value("val_psnr_blend", 0.0);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(source + ": bad fusion version manifest: " + e.what());
  }
  return m;
}

std::string FusionVersionDir(const std::string& versions_dir, uint64_t version) {
  char name[48];
  std::snprintf(name, sizeof(name), "%s%06llu", kPrefix, static_cast<unsigned long long>(version));
  return (fs::absolute(fs::path(versions_dir)) / name).string();
}

void WriteFusionVersion(const std::string& final_dir, const FusionVersionManifest& manifest,
                        const std::function<void(const std::string& temp_dir)>& write_payload) {
  if (fs::exists(final_dir))
    throw std::runtime_error("fusion version " + final_dir +
                             " already exists: versions are never rewritten");
  const std::string temp = final_dir + ".tmp." + std::to_string(::getpid());
  std::error_code ec;
  fs::remove_all(temp, ec);
  fs::create_directories(temp);
  try {
    write_payload(temp);
    {
      std::ofstream out(temp + "/manifest.json", std::ios::binary);
      out << manifest.ToJson();
      if (!out) throw std::runtime_error("cannot write " + temp + "/manifest.json");
    }
    for (const auto& e : fs::directory_iterator(temp))
      if (e.is_regular_file()) SyncPath(e.path().string());
    SyncPath(temp);
    fs::rename(temp, final_dir);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(temp, ec);
    throw std::runtime_error("cannot write fusion version " + final_dir + ": " + e.what());
  } catch (...) {
    fs::remove_all(temp, ec);
    throw;
  }
  SyncPath(fs::path(final_dir).parent_path().string());
}

FusionVersionManifest ReadFusionVersion(const std::string& dir) {
  const std::string path = dir + "/manifest.json";
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("fusion version " + dir +
                             ": no manifest.json (not a committed version folder)");
  std::ostringstream ss;
  ss << in.rdbuf();
  FusionVersionManifest m = FusionVersionManifest::FromJson(ss.str(), path);
  if (!fs::exists(fs::path(dir) / m.tsdf_file))
    throw std::runtime_error("fusion version " + dir + ": TSDF file " + m.tsdf_file + " missing");
  if (!m.refine_file.empty() && !fs::exists(fs::path(dir) / m.refine_file))
    throw std::runtime_error("fusion version " + dir + ": refinement file " + m.refine_file +
                             " missing");
  for (const std::string& f : m.submap_files)
    if (!fs::exists(fs::path(dir) / f))
      throw std::runtime_error("fusion version " + dir + ": submap file " + f + " missing");
  if (!m.keyframes_dir.empty() && !fs::is_directory(m.keyframes_dir))
    throw std::runtime_error("fusion version " + dir + ": keyframe folder " + m.keyframes_dir +
                             " missing");
  return m;
}

std::vector<uint64_t> ListFusionVersions(const std::string& versions_dir) {
  std::vector<uint64_t> out;
  if (!fs::is_directory(versions_dir)) return out;
  for (const auto& e : fs::directory_iterator(versions_dir)) {
    if (!e.is_directory()) continue;
    const uint64_t v = VersionOf(e.path().filename().string());
    if (v > 0) out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

int PruneFusionVersions(const std::string& versions_dir, int keep, double min_age_s) {
  if (keep < 1) throw std::invalid_argument("PruneFusionVersions: keep must be >= 1");
  int removed = 0;
  if (!fs::is_directory(versions_dir)) return 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(versions_dir)) {
    const std::string name = e.path().filename().string();
    if (e.is_directory() && name.rfind(kPrefix, 0) == 0 && name.find(".tmp.") != std::string::npos) {
      fs::remove_all(e.path(), ec);
      ++removed;
    }
  }
  const std::vector<uint64_t> versions = ListFusionVersions(versions_dir);
  const auto now = fs::file_time_type::clock::now();
  for (size_t i = 0; i + keep < versions.size(); ++i) {
    const std::string dir = FusionVersionDir(versions_dir, versions[i]);
    const auto written = fs::last_write_time(dir, ec);
    if (!ec && std::chrono::duration<double>(now - written).count() < min_age_s) continue;
    ec.clear();
    fs::remove_all(dir, ec);
    ++removed;
  }
  return removed;
}

}  // namespace p2i::model
