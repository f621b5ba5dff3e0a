/// @file cmd_info.cc
/// @brief `p2i info FILE.mcap`, like `ros2 bag info`: duration, topics, types, counts, rates,
/// size; for a file without summary (recorder killed) what was recovered and where it ends.
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "recording/mcap_reader.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

std::string Bytes(uint64_t n) {
  char buf[64];
  if (n < (1u << 10)) std::snprintf(buf, sizeof buf, "%llu B", static_cast<unsigned long long>(n));
  else if (n < (1u << 20)) std::snprintf(buf, sizeof buf, "%.1f KiB", n / 1024.0);
  else if (n < (1u << 30)) std::snprintf(buf, sizeof buf, "%.1f MiB", n / 1048576.0);
  else std::snprintf(buf, sizeof buf, "%.2f GiB", n / 1073741824.0);
  return buf;
}

std::string Stamp(uint64_t ns) {
  const std::time_t s = static_cast<std::time_t>(ns / 1000000000ull);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[96], out[128];
  std::strftime(buf, sizeof buf, "%b %e %Y %H:%M:%S", &tm);
  std::snprintf(out, sizeof out, "%s.%03llu UTC (%llu.%09llu)", buf,
                static_cast<unsigned long long>((ns / 1000000ull) % 1000),
                static_cast<unsigned long long>(ns / 1000000000ull),
                static_cast<unsigned long long>(ns % 1000000000ull));
  return out;
}

// --json: the summary with times in ns as strings.
void PrintJson(const std::string& path, const recording::McapSummary& s, double duration) {
  const auto& st = s.stats;
  nlohmann::json j = {{"file", path},
                      {"size", s.file_size},
                      {"duration_s", duration},
                      {"start_ns", std::to_string(st.message_start_time)},
                      {"end_ns", std::to_string(st.message_end_time)},
                      {"messages", st.message_count},
                      {"chunks", st.chunk_count},
                      {"compressed_bytes", s.compressed_bytes},
                      {"uncompressed_bytes", s.uncompressed_bytes},
                      {"has_summary", s.has_summary},
                      {"stop_reason", s.stop_reason},
                      {"readable_bytes", s.readable_bytes},
                      {"topics", nlohmann::json::array()}};
  for (const auto& [id, ch] : s.channels) {
    const auto sc = s.schemas.find(ch.schema_id);
    const auto cnt = st.channel_message_counts.find(id);
    const uint64_t n = cnt == st.channel_message_counts.end() ? 0 : cnt->second;
    j["topics"].push_back({{"topic", ch.topic},
                           {"type", sc == s.schemas.end() ? "" : sc->second.name},
                           {"count", n},
                           {"rate_hz", duration > 0 && n > 1 ? (n - 1) / duration : 0.0},
                           {"encoding", ch.message_encoding}});
  }
  std::printf("%s\n", j.dump(2).c_str());
}

// The `ros2 bag info` layout.
void PrintText(const std::string& path, const recording::McapSummary& s, double duration,
               const std::string& compression) {
  const auto& st = s.stats;
  std::printf("Files:             %s\n", path.c_str());
  std::printf("Bag size:          %s\n", Bytes(s.file_size).c_str());
  std::printf("Storage id:        mcap (library \"%s\"%s)\n", s.library.c_str(),
              s.profile.empty() ? "" : (", profile " + s.profile).c_str());
  std::printf("Duration:          %.3fs\n", duration);
  if (st.message_count) {
    std::printf("Start:             %s\n", Stamp(st.message_start_time).c_str());
    std::printf("End:               %s\n", Stamp(st.message_end_time).c_str());
  }
  std::printf("Messages:          %llu\n", static_cast<unsigned long long>(st.message_count));
  std::printf("Chunks:            %u (%s; %s compressed from %s)\n", st.chunk_count,
              compression.empty() ? "none" : compression.c_str(),
              Bytes(s.compressed_bytes).c_str(), Bytes(s.uncompressed_bytes).c_str());
  if (s.has_summary) {
    std::printf("Summary:           yes (chunk indexes, statistics)\n");
  } else {
    std::printf("Summary:           none (%s): recovered by scanning; readable up to byte %llu of %llu\n",
                s.stop_reason.empty() ? "data section complete, summary missing or damaged" : s.stop_reason.c_str(),
                static_cast<unsigned long long>(s.readable_bytes),
                static_cast<unsigned long long>(s.file_size));
  }
  std::printf("Topic information:");
  bool first = true;
  for (const auto& [id, ch] : s.channels) {
    const auto sc = s.schemas.find(ch.schema_id);
    const auto cnt = st.channel_message_counts.find(id);
    const uint64_t n = cnt == st.channel_message_counts.end() ? 0 : cnt->second;
    std::printf("%sTopic: %s | Type: %s | Count: %llu | Rate: %.2f Hz | Serialization Format: %s\n",
                first ? " " : "                   ", ch.topic.c_str(),
                sc == s.schemas.end() ? "(no schema)" : sc->second.name.c_str(),
                static_cast<unsigned long long>(n), duration > 0 ? (n > 1 ? (n - 1) / duration : 0) : 0.0,
                ch.message_encoding.c_str());
    first = false;
  }
  if (first) std::printf("\n");
}

int RunInfo(const std::vector<std::string>& args) {
  CLI::App app{"Summarise an MCAP recording (like `ros2 bag info`)", "p2i info"};
  std::string path;
  bool json = false;
  app.add_option("file", path, "FILE.mcap")->required();
  app.add_flag("--json", json, "Machine-readable output (times in ns as strings)");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  recording::McapReader reader;
  std::string error;
  if (!reader.Open(path, &error)) {
    std::fprintf(stderr, "p2i info: %s\n", error.c_str());
    return 1;
  }
  const auto& s = reader.Summary();
  const auto& st = s.stats;
  const double duration =
      st.message_count ? (st.message_end_time - st.message_start_time) / 1e9 : 0.0;
  std::string compression;
  for (const auto& [name, n] : s.chunks_by_compression)
    compression += (compression.empty() ? "" : ", ") + std::to_string(n) + " " +
                   (name.empty() ? "uncompressed" : name);
  if (json) {
    PrintJson(path, s, duration);
  } else {
    PrintText(path, s, duration, compression);
  }
  return 0;
}

}  // namespace

P2I_COMMAND("info", "Summarise an MCAP recording: info FILE.mcap", RunInfo);

}  // namespace p2i::tools
