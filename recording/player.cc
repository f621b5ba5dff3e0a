/// @file player.cc
/// @brief MCAP -> RawPublishers with the recorded log-time spacing divided by the rate.
#include "recording/player.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "msgs/codec.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/shutdown.h"
#include "recording/inline_blobs.h"
#include "recording/mcap_reader.h"
#include "recording/proto_schema.h"

namespace p2i::recording {

void PlayerOptions::Validate() const {
  if (input.empty()) throw std::invalid_argument("play: FILE.mcap is required");
  if (!(rate > 0)) throw std::invalid_argument("play: --rate must be > 0 (1 = recorded speed)");
  if (start_s < 0) throw std::invalid_argument("play: --start must be >= 0 s");
  if (delay_s < 0) throw std::invalid_argument("play: --delay must be >= 0 s");
  if (!(latch_period_s > 0)) throw std::invalid_argument("play: latch period must be > 0");
}

Player::Player(PlayerOptions options) : options_(std::move(options)) { options_.Validate(); }

namespace {

/// The publisher of one recorded channel.
struct PlayOut {
  const google::protobuf::Descriptor* type = nullptr;
  std::unique_ptr<runtime::RawPublisher> pub;
  bool latched = false;
};

/// One publisher per p2i channel of the file (restricted to options.topics when given); schemas
/// of other packages, e.g. foxglove.*, are views of the same data and are not republished.
std::map<uint16_t, PlayOut> MakePublishers(const McapSummary& summary,
                                           const PlayerOptions& options) {
  std::map<uint16_t, PlayOut> outs;
  for (const auto& [id, ch] : summary.channels) {
    const auto s = summary.schemas.find(ch.schema_id);
    if (s == summary.schemas.end() || s->second.encoding != "protobuf" ||
        s->second.name.rfind("p2i.msgs.pb.", 0) != 0)
      continue;
    if (!options.topics.empty() &&
        std::find(options.topics.begin(), options.topics.end(), ch.topic) == options.topics.end())
      continue;
    const auto* d = FindDescriptor(s->second.name);
    if (!d) continue;
    PlayOut o;
    o.type = d;
    runtime::PublisherOptions po;
    o.latched = std::find(options.latched_types.begin(), options.latched_types.end(),
                          s->second.name) != options.latched_types.end();
    po.latched = o.latched;
    po.latch_period_s = options.latch_period_s;
    const auto meta = ch.metadata.find("p2i_type");
    o.pub = std::make_unique<runtime::RawPublisher>(
        ch.topic, meta != ch.metadata.end() ? meta->second : d->name(), options.node_name, po);
    outs.emplace(id, std::move(o));
  }
  return outs;
}

/// Gives a recorded message a new seq and publish stamp from `pub` (a loop must not look like
/// latched duplicates); capture stamps, frame ids and payload stay as recorded. False when its
/// header cannot be read.
bool Restamp(msgs::WireMessage* wire, runtime::RawPublisher* pub, const std::string& node_name) {
  msgs::pb::HeaderOnly ho;
  std::string header_error;
  msgs::pb::Header h;
  if (!msgs::PeekHeader(wire->header, &h, &header_error)) return false;
  h.set_seq(pub->NextSeq());
  h.set_publish_stamp_ns(runtime::NowNs());
  h.set_publisher(node_name);
  *ho.mutable_header() = h;
  wire->header += ho.SerializeAsString();  // protobuf merge: the later header fields win
  return true;
}

}  // namespace

bool Player::Run(std::string* error, const PublishHook& on_publish) {
  McapReader reader;
  if (!reader.Open(options_.input, error)) return false;
  const McapSummary& summary = reader.Summary();
  std::map<uint16_t, PlayOut> outs = MakePublishers(summary, options_);
  if (outs.empty()) {
    *error = options_.input + ": no p2i channel to play" +
             (options_.topics.empty() ? "" : " among the requested --topics");
    return false;
  }
  using Clock = std::chrono::steady_clock;
  auto next_latch = Clock::now();
  auto republish_latched = [&] {
    if (Clock::now() < next_latch) return;
    next_latch = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(options_.latch_period_s));
    for (auto& [id, o] : outs)
      if (o.latched) o.pub->RepublishLatched();
  };
  runtime::Shutdown::WaitFor(std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(options_.delay_s)));
  const uint64_t first = summary.stats.message_start_time;
  const uint64_t start_at = first + static_cast<uint64_t>(options_.start_s * 1e9);
  do {
    if (runtime::Shutdown::Requested()) break;
    const auto t0 = Clock::now();
    const int64_t wall0 = runtime::NowNs();
    bool ok = reader.ReadMessages(
        [&](const mcap::Channel& ch, const mcap::Message& m) {
          if (runtime::Shutdown::Requested()) return false;
          auto it = outs.find(ch.id);
          if (it == outs.end() || m.log_time < start_at) {
            ++stats_.skipped;
            return true;
          }
          const auto offset = std::chrono::nanoseconds(
              static_cast<int64_t>(static_cast<double>(m.log_time - start_at) / options_.rate));
          const auto due = t0 + offset;
          while (Clock::now() < due && !runtime::Shutdown::Requested()) {
            republish_latched();
            const auto left = due - Clock::now();
            runtime::Shutdown::WaitFor(std::min<Clock::duration>(left, std::chrono::milliseconds(50)));
          }
          if (runtime::Shutdown::Requested()) return false;
          msgs::WireMessage wire;
          std::string why;
          if (!ExtractBlobs(it->second.type->full_name(), m.data, m.size, &wire, &why)) {
            ++stats_.unreadable;
            return true;
          }
          if (!Restamp(&wire, it->second.pub.get(), options_.node_name)) {
            ++stats_.unreadable;
            return true;
          }
          it->second.pub->Publish(wire);
          ++stats_.published;
          if (on_publish) {
            on_publish(ch.topic, wall0 + offset.count(), runtime::NowNs());
          }
          return true;
        },
        error);
    if (!ok) return false;
    stats_.stop_reason = reader.Summary().stop_reason;
    ++stats_.loops;
  } while (options_.loop);
  return true;
}

}  // namespace p2i::recording
