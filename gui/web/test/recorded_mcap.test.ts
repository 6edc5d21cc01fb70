import { type IReadable, McapIndexedReader } from "@mcap/core";
import { describe, expect, it } from "vitest";
import { ChunkCache } from "../src/session/mcap_cache";
import { decompressHandlers } from "../src/session/mcap_decompress";
import { spread, telegramFrame } from "../src/session/recorded_mcap";
import { mcapFile } from "./mcap_file";

const encode = (s: string) => new TextEncoder().encode(s);

/** A pltf.Telegram message as proxy/mcap_export.py writes it (telegram_message). */
function message(direction: string, kind: string, name: string, hex: string): Uint8Array {
  return encode(
    `{"timestamp":{"sec":1795000000,"nsec":2000128},"conn":1,"port":10002,"direction":"${direction}",` +
      `"kind":"${kind}","name":"${name}","hex":"${hex}","error":null}`,
  );
}

describe("a telegram message's frame", () => {
  it("reads direction, name and hex from the export's layout as JSON.parse would", () => {
    const data = message("reply", "frame", "CMD_GET_STATUS", "ff01fe02000009fc12");
    const found = telegramFrame(1.5, data);
    const body = JSON.parse(new TextDecoder().decode(data));
    expect(found?.name).toBe(body.name);
    expect(found?.frame.dir).toBe(body.direction);
    expect(found?.frame.t).toBe(1.5);
    expect(found?.frame.hex).toBe(body.hex);
  });

  it("is null for what is not a frame (a connection's opening, marked bytes)", () => {
    expect(telegramFrame(0, message("request", "open", "open", ""))).toBeNull();
  });

  it("parses a message of another layout whole", () => {
    const other = encode('{"name":"CMD_STOP","hex":"ff01","kind":"frame","direction":"request"}');
    expect(telegramFrame(2, other)).toEqual({ name: "CMD_STOP", frame: { t: 2, dir: "request", hex: "ff01" } });
    expect(telegramFrame(2, encode('{"name":"x","kind":"bytes","direction":"reply","hex":""}'))).toBeNull();
  });
});

describe("spread: the plots' points of a jump's history", () => {
  it("keeps everything up to n", () => {
    expect(spread([1, 2, 3], 3)).toEqual([1, 2, 3]);
    expect(spread([], 5)).toEqual([]);
  });

  it("picks n evenly spread, in order, the first and the last among them", () => {
    const xs = Array.from({ length: 101 }, (_, i) => i);
    expect(spread(xs, 5)).toEqual([0, 25, 50, 75, 100]);
    const many = spread(
      Array.from({ length: 10_000 }, (_, i) => i),
      300,
    );
    expect(many).toHaveLength(300);
    expect(many.at(-1)).toBe(9_999);
    expect(many[0]).toBe(0);
    expect(many.every((x, i) => i === 0 || x > many[i - 1])).toBe(true);
  });

  it("keeps the last one when only one is asked for", () => {
    expect(spread([1, 2, 3], 1)).toEqual([3]);
  });
});

/** A readable over bytes that counts its reads. */
function bytesReadable(bytes: Uint8Array): IReadable & { reads: number } {
  return {
    reads: 0,
    async size() {
      return BigInt(bytes.length);
    },
    async read(offset: bigint, size: bigint) {
      this.reads++;
      return bytes.slice(Number(offset), Number(offset + size));
    },
  };
}

describe("the chunk cache", () => {
  const file = Uint8Array.from({ length: 4096 }, (_, i) => i & 255);

  it("answers a read again from what it kept, and a chunk's decompression once", async () => {
    const inner = bytesReadable(file);
    const cache = new ChunkCache(inner, 1 << 20);
    let decompressed = 0;
    const handlers = cache.decompressing({
      zstd: (buf, size) => {
        decompressed++;
        return new Uint8Array(Number(size)).fill(buf[0]);
      },
    });
    for (let k = 0; k < 3; k++) {
      const raw = await cache.read(100n, 200n);
      expect([...raw.subarray(0, 3)]).toEqual([100, 101, 102]);
      // the reader hands the handler a copy of the chunk record's last field, its records
      const out = handlers.zstd(raw.slice(150), 1000n);
      expect(out.length).toBe(1000);
      expect(out[0]).toBe(250);
    }
    expect(inner.reads).toBe(1);
    expect(decompressed).toBe(1);
    // other bytes are decompressed, not answered from the kept chunk
    expect(handlers.zstd(Uint8Array.of(7, 8, 9), 1000n)[0]).toBe(7);
    const other = (await cache.read(1000n, 200n)).slice(150);
    other[0] ^= 1; // not the read's tail
    expect(handlers.zstd(other, 1000n)[0]).toBe(other[0]);
    expect(decompressed).toBe(3);
  });

  it("forgets the least recently used reads past its size", async () => {
    const inner = bytesReadable(file);
    const cache = new ChunkCache(inner, 1000);
    await cache.read(0n, 400n);
    await cache.read(1000n, 400n);
    await cache.read(0n, 400n); // used again: now the most recent
    await cache.read(2000n, 400n); // 1,200 bytes: the read at 1000 goes
    expect(inner.reads).toBe(3);
    await cache.read(0n, 400n);
    expect(inner.reads).toBe(3);
    await cache.read(1000n, 400n);
    expect(inner.reads).toBe(4);
  });
});

describe("the chunk cache under @mcap/core's reader", () => {
  it("decompresses each chunk once over two reads of the file, and the messages are the same", async () => {
    const cache = new ChunkCache(bytesReadable(await mcapFile("lz4", 2000)));
    const reader = await McapIndexedReader.Initialize({
      readable: cache,
      decompressHandlers: cache.decompressing(decompressHandlers),
    });
    const chunks = reader.chunkIndexes.length;
    expect(chunks).toBeGreaterThan(3);
    const read = async () => {
      const out: string[] = [];
      for await (const m of reader.readMessages({ validateCrcs: false })) {
        out.push(new TextDecoder().decode(m.data));
      }
      return out;
    };
    const first = await read();
    expect(cache.counts.decompressMisses).toBe(chunks);
    expect(await read()).toEqual(first);
    expect(first).toHaveLength(2000);
    expect(cache.counts.decompressMisses).toBe(chunks);
    expect(cache.counts.decompressHits).toBe(chunks);
  });
});
