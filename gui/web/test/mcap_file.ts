/** Test data: small MCAP files made with @mcap/core's writer, for the page's MCAP reader and its decompressors. */
import { McapWriter } from "@mcap/core";
import { compress as lz4 } from "lz4js";

/** An MCAP file of `count` JSON messages ({i, text}) on one channel, in chunks of ~16 KB compressed as
 * `compression` says ("" : none). */
export async function mcapFile(compression: "lz4" | "", count: number): Promise<Uint8Array> {
  const parts: Uint8Array[] = [];
  let at = 0n;
  const writable = {
    position: () => at,
    write: async (b: Uint8Array) => {
      parts.push(b.slice());
      at += BigInt(b.length);
    },
  };
  const compressChunk = (data: Uint8Array) =>
    compression === "lz4" ? { compression, compressedData: lz4(data) } : { compression, compressedData: data };
  const writer = new McapWriter({ writable, chunkSize: 16 * 1024, compressChunk });
  await writer.start({ profile: "", library: "test" });
  const channelId = await writer.registerChannel({
    topic: "/t",
    messageEncoding: "json",
    schemaId: 0,
    metadata: new Map(),
  });
  for (let i = 0; i < count; i++) {
    const data = new TextEncoder().encode(JSON.stringify({ i, text: "pltf ".repeat(i % 50) }));
    await writer.addMessage({ channelId, sequence: i, logTime: BigInt(i), publishTime: BigInt(i), data });
  }
  await writer.end();
  const out = new Uint8Array(Number(at));
  let k = 0;
  for (const p of parts) {
    out.set(p, k);
    k += p.length;
  }
  return out;
}
