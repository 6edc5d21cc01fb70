// A second, independent MCAP reader for tests/proxy/test_mcap_export.py: @mcap/core, the library Foxglove reads
// MCAP with (chunks compressed with zstd, lz4 or not at all). Usage: node read.mjs FILE. Prints one JSON object: what the file says about itself, read twice:
// - "stream": every record from start to end (McapStreamReader, CRCs checked): channels with their schemas,
//   messages per topic, whether log times ever go back within a channel, the time range;
// - "indexed": through the summary section (McapIndexedReader): the statistics record, the chunk indexes
//   (time range and messages per chunk, from each chunk's message indexes), and the messages per topic that
//   readMessages() finds through those indexes.
// A protobuf channel's messages are decoded as Foxglove decodes them: protobufjs, its types built from the
// FileDescriptorSet the schema record carries ("decoded": per topic, each message as plain JSON).
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress } from "fzstd";
import lz4 from "lz4js";
import { open, readFile } from "node:fs/promises";
import protobuf from "protobufjs";
import descriptor from "protobufjs/ext/descriptor/index.js";

// A chunk's compression as Foxglove reads it: zstd (fzstd) or lz4 (lz4js: the LZ4 frame format); none needs none.
const decompressHandlers = {
  zstd: (data, size) => decompress(data, new Uint8Array(Number(size))),
  lz4: (data, size) => lz4.decompress(data, Number(size)),
};
const path = process.argv[2];

function protobufType(schema) {
  const root = protobuf.Root.fromDescriptor(descriptor.FileDescriptorSet.decode(schema.data));
  return root.lookupType(schema.name);
}

function streamRead(bytes) {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  const schemas = new Map();
  const channels = new Map();
  const counts = {};
  const last = new Map();
  let monotonic = true;
  let start = null;
  let end = null;
  const types = new Map();
  const decoded = {};
  let rec;
  while ((rec = reader.nextRecord()) !== undefined) {
    if (rec.type === "Schema") schemas.set(rec.id, rec);
    if (rec.type === "Channel") channels.set(rec.id, rec);
    if (rec.type !== "Message") continue;
    const channel = channels.get(rec.channelId);
    const topic = channel.topic;
    counts[topic] = (counts[topic] ?? 0) + 1;
    if (channel.messageEncoding === "protobuf") {
      if (!types.has(channel.id)) types.set(channel.id, protobufType(schemas.get(channel.schemaId)));
      const type = types.get(channel.id);
      const message = type.toObject(type.decode(rec.data), { longs: Number, defaults: true, arrays: true });
      (decoded[topic] ??= []).push(message);
    }
    if (last.has(rec.channelId) && rec.logTime < last.get(rec.channelId)) monotonic = false;
    last.set(rec.channelId, rec.logTime);
    if (start === null || rec.logTime < start) start = rec.logTime;
    if (end === null || rec.logTime > end) end = rec.logTime;
  }
  const described = [...channels.values()].map((c) => {
    const s = schemas.get(c.schemaId);
    return {
      topic: c.topic,
      messageEncoding: c.messageEncoding,
      schemaName: s?.name ?? null,
      schemaEncoding: s?.encoding ?? null,
      schemaBytes: s ? s.data.length : 0,
    };
  });
  return {
    done: reader.done(),
    channels: described,
    counts,
    monotonic,
    start: String(start),
    end: String(end),
    decoded,
  };
}

async function indexedRead() {
  const fh = await open(path, "r");
  const readable = {
    size: async () => BigInt((await fh.stat()).size),
    read: async (offset, length) => {
      const buf = new Uint8Array(Number(length));
      await fh.read(buf, 0, Number(length), Number(offset));
      return buf;
    },
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const st = reader.statistics;
  const channelMessageCounts = {};
  for (const [id, n] of st.channelMessageCounts) channelMessageCounts[reader.channelsById.get(id).topic] = String(n);
  const chunks = reader.chunkIndexes.map((c) => ({
    start: String(c.messageStartTime),
    end: String(c.messageEndTime),
    compression: c.compression,
  }));
  const counts = {};
  for await (const m of reader.readMessages()) {
    const topic = reader.channelsById.get(m.channelId).topic;
    counts[topic] = (counts[topic] ?? 0) + 1;
  }
  await fh.close();
  return {
    statistics: {
      messageCount: String(st.messageCount),
      channelCount: st.channelCount,
      schemaCount: st.schemaCount,
      chunkCount: st.chunkCount,
      messageStartTime: String(st.messageStartTime),
      messageEndTime: String(st.messageEndTime),
      channelMessageCounts,
    },
    chunks,
    counts,
  };
}

const out = { stream: streamRead(await readFile(path)), indexed: await indexedRead() };
process.stdout.write(JSON.stringify(out) + "\n");
