/// @file mcap_test.cc
/// @brief McapWriter -> McapReader round trips (zstd, lz4, none), the summary, recovery of
/// truncated and corrupted files without their summary.
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>

#include "recording/compression.h"
#include "recording/mcap_reader.h"
#include "recording/mcap_writer.h"
#include "tests/read_file.h"
#include "tests/recording/recording_test_util.h"

using namespace p2i::recording;
namespace rt = p2i::recording::testing;

namespace {

struct Got {
  std::string topic;
  uint32_t seq;
  uint64_t log_time, publish_time;
  std::string data;
};

std::vector<Got> ReadAll(McapReader& r) {
  std::vector<Got> out;
  std::string error;
  REQUIRE(r.ReadMessages(
      [&](const mcap::Channel& ch, const mcap::Message& m) {
        out.push_back({ch.topic, m.sequence, m.log_time, m.publish_time,
                       std::string(reinterpret_cast<const char*>(m.data), m.size)});
        return true;
      },
      &error));
  return out;
}

/// 3 channels x n messages of varied sizes; message i of channel c has payload Payload(c, i).
std::string Payload(int c, int i) {
  std::string s(100 + (i * 37 + c * 1000) % 5000, '\0');
  for (size_t k = 0; k < s.size(); ++k) s[k] = static_cast<char>((k * 31 + i + c) % 251);
  return s;
}

void WriteSample(const std::string& path, const McapWriterOptions& o, int n) {
  McapWriter w;
  w.Open(path, o);
  const uint16_t s = w.AddSchema("test.Thing", "protobuf", "schema-bytes");
  const uint16_t ch[3] = {w.AddChannel(s, "/a", "protobuf", {{"k", "v"}}),
                          w.AddChannel(s, "/b", "protobuf"), w.AddChannel(s, "/c", "protobuf")};
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      const std::string p = Payload(c, i);
      w.Write(ch[c], i + 1, 1000 + i * 10 + c, 900 + i * 10 + c, p.data(), p.size());
    }
  }
  w.Close();
}

}  // namespace

TEST_CASE("MCAP: written messages read back identical with zstd, lz4 and none", "[unit]") {
  const std::string dir = rt::TempDir("mcap_rt");
  for (const std::string comp : {"zstd", "lz4", ""}) {
    INFO("compression '" << comp << "'");
    McapWriterOptions o;
    o.compression = comp;
    o.chunk_size = 16 * 1024;  // many chunks
    const std::string path = dir + "/rt_" + (comp.empty() ? "none" : comp) + ".mcap";
    WriteSample(path, o, 200);
    McapReader r;
    std::string error;
    REQUIRE(r.Open(path, &error));
    const auto& s = r.Summary();
    CHECK(s.has_summary);
    CHECK(s.has_footer);
    CHECK(s.library == "p2i");
    CHECK(s.stats.message_count == 600);
    CHECK(s.stats.channel_count == 3);
    CHECK(s.stats.schema_count == 1);
    CHECK(s.stats.chunk_count > 10);
    CHECK(s.stats.message_start_time == 1000);
    CHECK(s.stats.message_end_time == 1000 + 199 * 10 + 2);
    CHECK(s.stats.channel_message_counts.at(2) == 200);
    REQUIRE(s.channels.size() == 3);
    CHECK(s.channels.at(1).metadata.at("k") == "v");
    CHECK(s.schemas.at(1).name == "test.Thing");
    CHECK(s.schemas.at(1).data == "schema-bytes");
    CHECK(s.chunks_by_compression.at(comp) == s.stats.chunk_count);
    if (!comp.empty()) CHECK(s.compressed_bytes < s.uncompressed_bytes);
    const auto got = ReadAll(r);
    REQUIRE(got.size() == 600);
    for (size_t k = 0; k < got.size(); ++k) {
      const int i = static_cast<int>(k / 3), c = static_cast<int>(k % 3);
      CHECK(got[k].topic == std::string(1, '/') + static_cast<char>('a' + c));
      CHECK(got[k].seq == static_cast<uint32_t>(i + 1));
      CHECK(got[k].log_time == static_cast<uint64_t>(1000 + i * 10 + c));
      CHECK(got[k].publish_time == static_cast<uint64_t>(900 + i * 10 + c));
      if (got[k].data != Payload(c, i)) FAIL("payload differs at message " << k);
    }
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("MCAP: file layout follows the spec (magic, header, data end, footer)", "[unit]") {
  const std::string dir = rt::TempDir("mcap_layout");
  WriteSample(dir + "/f.mcap", McapWriterOptions(), 5);
  const std::string b = p2i::testing::ReadFile(dir + "/f.mcap");
  REQUIRE(b.size() > 16 + 29);
  CHECK(std::memcmp(b.data(), mcap::kMagic, 8) == 0);
  CHECK(std::memcmp(b.data() + b.size() - 8, mcap::kMagic, 8) == 0);
  CHECK(static_cast<uint8_t>(b[8]) == 0x01);                 // Header
  CHECK(static_cast<uint8_t>(b[b.size() - 8 - 29]) == 0x02);  // Footer
  uint64_t summary_start = 0;
  std::memcpy(&summary_start, b.data() + b.size() - 8 - 20, 8);
  // The record just before the summary is DataEnd (opcode 0x0F, 4-byte body) whose CRC covers
  // every byte before it.
  REQUIRE(summary_start > 13);
  const size_t data_end = summary_start - 13;
  CHECK(static_cast<uint8_t>(b[data_end]) == 0x0F);
  uint32_t crc = 0;
  std::memcpy(&crc, b.data() + data_end + 9, 4);
  CHECK(crc == Crc32(0, b.data(), data_end));
  std::filesystem::remove_all(dir);
}

TEST_CASE("MCAP: a truncated file (writer killed) is read up to its last complete chunk",
          "[unit]") {
  const std::string dir = rt::TempDir("mcap_trunc");
  McapWriterOptions o;
  o.chunk_size = 8 * 1024;
  WriteSample(dir + "/full.mcap", o, 100);
  const std::string full = p2i::testing::ReadFile(dir + "/full.mcap");
  McapReader whole;
  std::string error;
  REQUIRE(whole.Open(dir + "/full.mcap", &error));
  const uint64_t summary_at = whole.Summary().readable_bytes;
  uint64_t last_count = 0;
  int checked = 0;
  // Cut points from just after the Header to the end of the data section (a stride keeps
  // it fast): opens, reads a prefix of the messages in order, never more than before the cut.
  for (size_t cut = 40; cut < summary_at; cut += 97) {  // from just after the Header record
    rt::WriteFile(dir + "/cut.mcap", full.substr(0, cut));
    McapReader r;
    REQUIRE(r.Open(dir + "/cut.mcap", &error));
    CHECK_FALSE(r.Summary().has_summary);
    CHECK_FALSE(r.Summary().stop_reason.empty());
    const auto got = ReadAll(r);
    CHECK(got.size() == r.Summary().stats.message_count);
    CHECK(got.size() >= last_count);  // more bytes never give fewer messages
    last_count = got.size();
    for (size_t k = 0; k < got.size(); ++k) {
      if (got[k].data != Payload(static_cast<int>(k % 3), static_cast<int>(k / 3)))
        FAIL("payload differs at message " << k << " of a file cut at " << cut);
    }
    ++checked;
  }
  CHECK(checked > 100);
  CHECK(last_count > 250);  // nearly all 300: only the last chunk can be missing
  // Cut inside the last chunk record: the stop reason names the truncated chunk.
  rt::WriteFile(dir + "/cut.mcap", full.substr(0, summary_at - 200));
  McapReader r;
  REQUIRE(r.Open(dir + "/cut.mcap", &error));
  CHECK(r.Summary().stop_reason.find("truncated") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("MCAP: a corrupted chunk stops the scan at that chunk (CRC), never a crash",
          "[unit]") {
  const std::string dir = rt::TempDir("mcap_corrupt");
  McapWriterOptions o;
  o.compression = "";  // a flipped byte would otherwise fail decompression, not the CRC
  o.chunk_size = 8 * 1024;
  WriteSample(dir + "/f.mcap", o, 60);
  std::string b = p2i::testing::ReadFile(dir + "/f.mcap");
  McapReader ok;
  std::string error;
  REQUIRE(ok.Open(dir + "/f.mcap", &error));
  const uint64_t data_bytes = ok.Summary().readable_bytes;
  b[data_bytes / 2] ^= 0x5a;
  // Without its footer the reader must scan; with the flipped byte it stops at that chunk.
  rt::WriteFile(dir + "/bad.mcap", b.substr(0, data_bytes));
  McapReader r;
  REQUIRE(r.Open(dir + "/bad.mcap", &error));
  CHECK(r.Summary().stats.message_count < 180);
  CHECK(r.Summary().stop_reason.find("Chunk") != std::string::npos);
  // Random garbage and non-MCAP files: clear errors.
  rt::WriteFile(dir + "/junk.mcap", "hello, not mcap");
  McapReader j;
  CHECK_FALSE(j.Open(dir + "/junk.mcap", &error));
  CHECK(error.find("not an MCAP file") != std::string::npos);
  CHECK_FALSE(j.Open(dir + "/missing.mcap", &error));
  // Flipped bytes anywhere: Open + ReadMessages never crash.
  for (size_t at = 0; at < b.size(); at += b.size() / 300 + 1) {
    std::string m = b;
    m[at] = static_cast<char>(m[at] ^ 0xff);
    rt::WriteFile(dir + "/m.mcap", m);
    McapReader x;
    if (x.Open(dir + "/m.mcap", &error)) {
      x.ReadMessages([](const mcap::Channel&, const mcap::Message&) { return true; }, &error);
    }
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("MCAP writer options are validated with the field name", "[unit]") {
  McapWriterOptions o;
  o.compression = "gzip";
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("compression"));
  o = McapWriterOptions();
  o.chunk_size = 10;
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("chunk_size"));
  McapWriter w;
  CHECK_THROWS_WITH(w.Open("/nonexistent_dir_p2i/x.mcap"), Catch::Contains("cannot create"));
}
