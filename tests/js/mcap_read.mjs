// Reads a p2i MCAP recording with @mcap/core (the MCAP project's own TypeScript reader) and
// checks it against `p2i info --json` of the same file: schemas, channels, message counts,
// log times; decodes the p2i and Foxglove messages with protobufjs from the schemas embedded
// in the file (FileDescriptorSets).
//   node mcap_read.mjs FILE.mcap INFO.json
import { readFileSync } from "node:fs";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "@foxglove/wasm-lz4";
import protobuf from "protobufjs";
import descriptor from "protobufjs/ext/descriptor/index.js";

const [file, infoFile] = process.argv.slice(2);
const bytes = new Uint8Array(readFileSync(file));
const info = JSON.parse(readFileSync(infoFile, "utf8"));
await zstd.isLoaded;
await lz4.isLoaded;
const decompressHandlers = {
  zstd: (buffer, size) => zstd.decompress(buffer, Number(size)),
  lz4: (buffer, size) => lz4(buffer, Number(size)),
};
const fail = (msg) => {
  console.error("FAIL: " + msg);
  process.exit(1);
};
const check = (cond, msg) => {
  if (!cond) fail(msg);
};

const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
check(reader.chunkIndexes.length > 0, "no chunk indexes");
check(reader.statistics !== undefined, "no statistics record");
check(Number(reader.statistics.messageCount) === info.messages,
      `statistics.messageCount ${reader.statistics.messageCount} != p2i info ${info.messages}`);

const roots = new Map();  // schema id -> protobuf Root
const typeOf = (schema) => {
  if (!roots.has(schema.id)) {
    const set = descriptor.FileDescriptorSet.decode(schema.data);
    roots.set(schema.id, protobuf.Root.fromDescriptor(set));
  }
  return roots.get(schema.id).lookupType(schema.name);
};

const counts = new Map();
const lastLog = new Map();
let decodedFrames = 0, decodedImages = 0;
for await (const m of reader.readMessages({ validateCrcs: true })) {
  const ch = reader.channelsById.get(m.channelId);
  const schema = reader.schemasById.get(ch.schemaId);
  check(ch.messageEncoding === "protobuf" && schema.encoding === "protobuf", "encodings");
  counts.set(ch.topic, (counts.get(ch.topic) ?? 0) + 1);
  check(m.logTime >= (lastLog.get(ch.topic) ?? 0n), `log times go back on ${ch.topic}`);
  lastLog.set(ch.topic, m.logTime);
  const msg = typeOf(schema).decode(m.data);
  if (schema.name === "p2i.msgs.pb.RgbdFrame") {
    const info = msg.cameraInfo ?? msg.camera_info;  // protobufjs keeps descriptor names
    const w = info.width, h = info.height;
    check(msg.rgb.data.length === w * h * 3, `rgb pixels ${msg.rgb.data.length} != ${w}x${h}x3`);
    check(msg.depth.data.length === msg.depth.height * msg.depth.step, "depth pixels");
    check(msg.header.type === 3 || msg.header.type === "RGBD_FRAME", "header.type");
    check(Number(msg.header.publishStampNs ?? msg.header.publish_stamp_ns) > 0, "publish stamp");
    decodedFrames++;
  } else if (schema.name === "foxglove.RawImage") {
    check(msg.width > 0 && msg.data.length === msg.height * msg.step, "RawImage size");
    check(["rgb8", "16UC1"].includes(msg.encoding), "RawImage encoding " + msg.encoding);
    decodedImages++;
  }
}
for (const t of info.topics) {
  check((counts.get(t.topic) ?? 0) === t.count,
        `${t.topic}: @mcap/core read ${counts.get(t.topic) ?? 0}, p2i info says ${t.count}`);
  const ch = [...reader.channelsById.values()].find((c) => c.topic === t.topic);
  check(reader.schemasById.get(ch.schemaId).name === t.type, `${t.topic} schema name`);
}
check(reader.statistics.messageStartTime === BigInt(info.start_ns), "start time");
check(reader.statistics.messageEndTime === BigInt(info.end_ns), "end time");
check(decodedFrames > 0, "no RgbdFrame decoded");

// The streaming reader (no index) agrees on the count.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
let streamed = 0;
for (let r; (r = stream.nextRecord()); ) if (r.type === "Message") streamed++;
check(stream.done(), "stream reader did not reach the end magic");
check(streamed === info.messages, `stream reader read ${streamed} messages`);
console.log(JSON.stringify({ ok: true, messages: info.messages, frames: decodedFrames,
                             foxglove_images: decodedImages, chunks: reader.chunkIndexes.length }));
