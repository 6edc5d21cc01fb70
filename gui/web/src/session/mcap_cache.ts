/**
 * The MCAP reader's chunks kept between seeks (recorded_mcap.ts): an @mcap/core IReadable that keeps what it read,
 * by offset, in a small LRU, and decompress handlers that keep each chunk's decompressed bytes beside its
 * compressed ones, so a chunk read again (the next seek in the same stretch of the recording, a play's steps, a
 * telegram looked up at a time the seek already read) costs neither a request nor a decompression.
 *
 * Rules:
 * - A read is kept by its offset and size; the least recently used reads go first once the kept bytes (compressed
 *   and decompressed together) pass `maxBytes`.
 * - McapIndexedReader parses a chunk record out of the bytes the readable returned and hands the handler a
 *   subarray of them, so the handler finds its read by the bytes' ArrayBuffer and offset; a chunk whose bytes are
 *   no longer kept is decompressed again.
 */
import type { IReadable, McapTypes } from "@mcap/core";

interface Kept {
  key: string;
  bytes: Uint8Array;
  /** the decompressed chunks inside `bytes`, by the compressed records' offset in its buffer */
  out: Map<number, Uint8Array>;
  weight: number;
}

export class ChunkCache implements IReadable {
  private kept = new Map<string, Kept>();
  private byBuffer = new WeakMap<ArrayBufferLike, Kept>();
  private total = 0;
  /** reads and decompressions answered from what was kept, and those that were not (for tests and benchmarks) */
  readonly counts = { readHits: 0, readMisses: 0, decompressHits: 0, decompressMisses: 0 };

  constructor(
    readonly inner: IReadable,
    readonly maxBytes = 64 * 1024 * 1024,
  ) {}

  size(): Promise<bigint> {
    return this.inner.size();
  }

  async read(offset: bigint, size: bigint): Promise<Uint8Array> {
    const key = `${offset}+${size}`;
    const hit = this.kept.get(key);
    if (hit !== undefined) {
      this.kept.delete(key); // to the most recent end
      this.kept.set(key, hit);
      this.counts.readHits++;
      return hit.bytes;
    }
    this.counts.readMisses++;
    const bytes = await this.inner.read(offset, size);
    const kept: Kept = { key, bytes, out: new Map(), weight: bytes.byteLength };
    this.kept.set(key, kept);
    this.byBuffer.set(bytes.buffer, kept);
    this.grow(kept.weight);
    return bytes;
  }

  /** `handlers` keeping their output beside the bytes it came from. */
  decompressing(handlers: McapTypes.DecompressHandlers): McapTypes.DecompressHandlers {
    const out: McapTypes.DecompressHandlers = {};
    for (const [name, handler] of Object.entries(handlers)) {
      out[name] = (buf, size) => {
        const kept = this.byBuffer.get(buf.buffer);
        const done = kept?.out.get(buf.byteOffset);
        if (done !== undefined) {
          this.counts.decompressHits++;
          return done;
        }
        this.counts.decompressMisses++;
        const bytes = handler(buf, size);
        if (kept !== undefined && this.kept.get(kept.key) === kept) {
          kept.out.set(buf.byteOffset, bytes);
          kept.weight += bytes.byteLength;
          this.grow(bytes.byteLength);
        }
        return bytes;
      };
    }
    return out;
  }

  private grow(by: number): void {
    this.total += by;
    for (const [key, old] of this.kept) {
      if (this.total <= this.maxBytes || this.kept.size <= 1) {
        break;
      }
      this.kept.delete(key);
      this.total -= old.weight;
    }
  }
}
