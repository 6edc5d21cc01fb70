/**
 * The MCAP reader's chunks kept between seeks (recorded_mcap.ts): an @mcap/core IReadable that keeps what it read,
 * by offset, in a small LRU, and decompress handlers that keep each chunk's decompressed bytes beside its
 * compressed ones, so a chunk read again (the next seek in the same stretch of the recording, a play's steps, a
 * telegram looked up at a time the seek already read) costs neither a request nor a decompression.
 *
 * Rules:
 * - A read is kept by its offset and size; the least recently used reads go first once the kept bytes (compressed
 *   and decompressed together) pass `maxBytes`.
 * - McapIndexedReader reads a chunk record whole and at once hands the handler a copy of its records, the
 *   record's last field: the handler finds its read among the last few returned, as the one whose bytes end with
 *   the records (compared byte for byte: ~1 ms against ~60 ms of zstd for a 4 MiB chunk); a chunk whose bytes are
 *   no longer kept is decompressed again.
 */
import type { IReadable, McapTypes } from "@mcap/core";

interface Kept {
  key: string;
  bytes: Uint8Array;
  /** the chunk's records decompressed (the read is one chunk record, its records at its end) */
  out: Uint8Array | null;
  weight: number;
}

/** How many of the last reads a handler looks among for the chunk it is handed. */
const RECENT = 4;

/** Whether `whole` ends with `tail`. */
export function endsWith(whole: Uint8Array, tail: Uint8Array): boolean {
  const at = whole.length - tail.length;
  if (at < 0) {
    return false;
  }
  for (let i = tail.length - 1; i >= 0; i--) {
    if (whole[at + i] !== tail[i]) {
      return false;
    }
  }
  return true;
}

export class ChunkCache implements IReadable {
  private kept = new Map<string, Kept>();
  private recent: Kept[] = [];
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
      this.returned(hit);
      return hit.bytes;
    }
    this.counts.readMisses++;
    const bytes = await this.inner.read(offset, size);
    const kept: Kept = { key, bytes, out: null, weight: bytes.byteLength };
    this.kept.set(key, kept);
    this.grow(kept.weight);
    this.returned(kept);
    return bytes;
  }

  private returned(kept: Kept): void {
    this.recent = [kept, ...this.recent.filter((k) => k !== kept)].slice(0, RECENT);
  }

  /** `handlers` keeping their output beside the bytes it came from. */
  decompressing(handlers: McapTypes.DecompressHandlers): McapTypes.DecompressHandlers {
    const out: McapTypes.DecompressHandlers = {};
    for (const [name, handler] of Object.entries(handlers)) {
      out[name] = (buf, size) => {
        const kept = this.recent.find(
          (k) => (k.out === null || k.out.length === Number(size)) && endsWith(k.bytes, buf),
        );
        if (kept?.out) {
          this.counts.decompressHits++;
          return kept.out;
        }
        this.counts.decompressMisses++;
        const bytes = handler(buf, size);
        if (kept !== undefined && this.kept.get(kept.key) === kept) {
          kept.out = bytes;
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
