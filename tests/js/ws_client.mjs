// Connects @foxglove/ws-protocol's FoxgloveClient (the protocol authors' client, over the `ws`
// package) to p2i_foxglove_bridge: N clients subscribe to a p2i RgbdFrame topic and its
// foxglove.RawImage channel, decode messages with the advertised schemas, check subscription
// ids and timestamps; one of them also sends bad requests (status errors expected, connection
// kept) and unsubscribes (no more messages on that subscription).
//   node ws_client.mjs ws://127.0.0.1:PORT TOPIC N_CLIENTS
import WebSocket from "ws";
import wsProtocol from "@foxglove/ws-protocol";
const { FoxgloveClient } = wsProtocol;
import protobuf from "protobufjs";
import descriptor from "protobufjs/ext/descriptor/index.js";

const [url, topic, nArg] = process.argv.slice(2);
const nClients = Number(nArg ?? 1);
const want = 5;
const fail = (msg) => {
  console.error("FAIL: " + msg);
  process.exit(1);
};
setTimeout(() => fail("timed out (hang guard)"), 30000).unref();

const decoderFor = (channel) => {
  const set = descriptor.FileDescriptorSet.decode(Buffer.from(channel.schema, "base64"));
  return protobuf.Root.fromDescriptor(set).lookupType(channel.schemaName);
};

function runClient(index) {
  return new Promise((resolve) => {
    const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
    const client = new FoxgloveClient({ ws });
    const subs = new Map();  // subscription id -> {channel, decoder, got}
    let serverName = null, statusErrors = 0, unsubscribed = null, afterUnsub = 0, done = false;
    let lastAfterUnsub = 0;
    client.on("serverInfo", (info) => { serverName = info.name; });
    client.on("status", (s) => { if (s.level === 2) statusErrors++; });
    client.on("error", (e) => fail(`client ${index}: ${e}`));
    client.on("advertise", (channels) => {
      for (const c of channels) {
        const isRaw = c.topic === topic && c.schemaName === "p2i.msgs.pb.RgbdFrame";
        const isFox = c.topic === topic + "/foxglove/rgb" && c.schemaName === "foxglove.RawImage";
        if (!isRaw && !isFox) continue;
        if (c.encoding !== "protobuf") fail(`channel ${c.topic} encoding ${c.encoding}`);
        const id = client.subscribe(c.id);
        subs.set(id, { channel: c, decoder: decoderFor(c), got: 0, last: 0n });
      }
      if (index === 0 && subs.size > 0 && statusErrors === 0) {
        ws.send("{not json");
        ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 99, channelId: 987654 }] }));
        ws.send(JSON.stringify({ op: "fly" }));
        ws.send(new Uint8Array([1, 2, 3]));
      }
    });
    client.on("message", ({ subscriptionId, timestamp, data }) => {
      if (subscriptionId === unsubscribed) { afterUnsub++; lastAfterUnsub = Date.now(); return; }
      const s = subs.get(subscriptionId);
      if (!s) fail(`client ${index}: message for unknown subscription ${subscriptionId}`);
      const now = BigInt(Date.now()) * 1000000n;
      const ts = BigInt(timestamp);
      if (ts < s.last) fail("timestamps go back");
      if (ts > now + 5000000000n || ts < now - 60000000000n) fail(`timestamp ${ts} far from now`);
      s.last = ts;
      const msg = s.decoder.decode(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
      if (s.channel.schemaName === "p2i.msgs.pb.RgbdFrame") {
        if (msg.rgb.data.length !== msg.rgb.height * msg.rgb.step) fail("RgbdFrame rgb size");
      } else if (msg.encoding !== "rgb8" || msg.data.length !== msg.height * msg.step) {
        fail("RawImage content");
      }
      s.got++;
      const all = [...subs.values()].every((x) => x.got >= want);
      if (all && !done) {
        done = true;
        if (index === 0 && statusErrors < 4) fail(`expected 4 status errors, got ${statusErrors}`);
        // Unsubscribe one; later messages on it would be a bug (counted below).
        unsubscribed = [...subs.keys()][0];
        client.unsubscribe(unsubscribed);
        setTimeout(() => {
          client.close();
          // Messages already queued when unsubscribing may still arrive; after 500 ms none may.
          const quietMs = lastAfterUnsub ? Date.now() - lastAfterUnsub : 1e9;
          resolve({ index, serverName, statusErrors, afterUnsub, quietMs,
                    got: [...subs.values()].map((x) => [x.channel.topic, x.got]) });
        }, 1200);
      }
    });
  });
}

const results = await Promise.all([...Array(nClients).keys()].map(runClient));
for (const r of results) {
  if (r.serverName !== "p2i_foxglove_bridge") fail(`serverInfo name ${r.serverName}`);
  if (r.quietMs < 500) fail(`client ${r.index}: messages still arrive after unsubscribe`);
}
console.log(JSON.stringify({ ok: true, clients: results }));
process.exit(0);
