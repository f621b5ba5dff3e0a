/// @file cmd_record.cc
/// @brief `p2i record [TOPIC... | -a] -o FILE.mcap`, like `ros2 bag record` (docs/RECORDING.md).
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "nodes/runtime/shutdown.h"
#include "recording/recorder.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunRecord(const std::vector<std::string>& args) {
  CLI::App app{"Record topics into an MCAP file (protobuf schemas embedded, chunked, compressed, "
               "indexed). Stops on Ctrl-C / SIGTERM, or after --duration.",
               "p2i record"};
  recording::RecorderOptions o;
  double duration_s = 0;
  std::string compression = o.mcap.compression;
  double chunk_mb = static_cast<double>(o.mcap.chunk_size) / (1 << 20);
  app.add_option("topics", o.topics, "Topics to record (absolute names)");
  app.add_flag("-a,--all", o.all, "Record every topic (re-discovered while recording)");
  app.add_option("-o,--output", o.output, "Output file (FILE.mcap)")->required();
  app.add_flag("--overwrite", o.overwrite, "Replace the output file if it exists");
  app.add_flag("--foxglove", o.foxglove,
               "Also write Foxglove channels (RawImage, CameraCalibration, FrameTransform, "
               "PoseInFrame) beside p2i's own channels");
  app.add_option("--compression", compression, "zstd | lz4 | none")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  app.add_option("--compression-level", o.mcap.compression_level, "zstd level (1 = fastest)");
  app.add_option("--chunk-size", chunk_mb, "MiB of uncompressed records per chunk");
  app.add_option("--chunk-age", o.mcap.chunk_max_age_s,
                 "s: write a chunk at least this often (what a kill can lose)");
  app.add_flag("--fsync", o.mcap.fsync_chunks, "fsync after every chunk (power-loss safety)");
  app.add_option("--duration", duration_s, "Stop after S seconds (0 = until stopped)");
  app.add_option("--queue", o.queue_messages, "Receive queue per topic (messages)");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  o.mcap.compression = compression == "none" ? "" : compression;
  o.mcap.chunk_size = static_cast<size_t>(chunk_mb * (1 << 20));
  for (auto& t : o.topics)
    if (!t.empty() && t[0] != '/') t = "/" + t;
  runtime::Shutdown::InstallSignalHandlers();
  try {
    recording::Recorder rec(o);
    rec.Start();
    std::fprintf(stderr, "p2i record: writing %s (%s)\n", o.output.c_str(),
                 o.all ? "all topics" : (std::to_string(o.topics.size()) + " topic(s)").c_str());
    const auto start = std::chrono::steady_clock::now();
    while (!runtime::Shutdown::Requested()) {
      if (duration_s > 0 && std::chrono::steady_clock::now() - start >=
                                std::chrono::duration<double>(duration_s))
        break;
      rec.SpinOnce(std::chrono::milliseconds(50));
    }
    rec.Stop();
    std::fprintf(stderr, "p2i record: %llu messages, %.1f MiB in %s\n",
                 static_cast<unsigned long long>(rec.MessagesWritten()),
                 static_cast<double>(rec.BytesWritten()) / (1 << 20), o.output.c_str());
    for (const auto& [topic, s] : rec.Stats()) {
      std::fprintf(stderr, "  %-40s %8llu msgs  dropped %llu  malformed %llu  [%s]\n",
                   topic.c_str(), static_cast<unsigned long long>(s.messages),
                   static_cast<unsigned long long>(s.dropped),
                   static_cast<unsigned long long>(s.malformed),
                   s.type.empty() ? "no messages" : s.type.c_str());
    }
    if (!rec.LastError().empty())
      std::fprintf(stderr, "p2i record: last unwritable message: %s\n", rec.LastError().c_str());
  } catch (const std::invalid_argument& e) {  // a bad option value: usage/config (exit 2)
    std::fprintf(stderr, "p2i record: %s\n", e.what());
    return 2;
} catch (const std::exception& e) {
    std::fprintf(stderr, "p2i record: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

P2I_COMMAND("record", "Record topics into an MCAP file: record [TOPIC... | -a] -o FILE.mcap",
            RunRecord);

}  // namespace p2i::tools
