/**
 * An MCAP recording read in the page (pltf gui --session FILE.mcap, issue 35), as Foxglove reads one: @mcap/core's
 * McapIndexedReader over HTTP range requests (the gateway serves the file: GET /recording.mcap), zstd chunks
 * decompressed with fzstd. The frames are the raw telegrams' channel of `pltf export --mcap` (proxy/mcap_export.py:
 * /pltf/telegrams, one JSON message per frame with its direction, name and hex); the other channels are for
 * Foxglove.
 *
 * Rules:
 * - On opening, the channel is read once and only each frame's log time, direction and name are kept (the
 *   index); `stateAt(t)` then bisects each reply name's times and reads just those messages back by their time.
 *   Chunks are read on demand; nothing holds the whole file.
 * - Times are the messages' log times (ns); the recording's start and end are the first and last of the channel.
 */
import { McapIndexedReader } from "@mcap/core";
import type { IReadable } from "@mcap/core";
import { decompress } from "fzstd";
import type { RecordedEvent, RecordedFrame, RecordedState, RecordingInfo, RecordingSource } from "./recorded";

export const TELEGRAMS = "/pltf/telegrams";

/** The file over HTTP: its size from a one-byte range, then the ranges McapIndexedReader asks for. */
export class HttpReadable implements IReadable {
  private length: bigint | null = null;
  constructor(readonly url: string) {}

  async size(): Promise<bigint> {
    if (this.length === null) {
      const r = await fetch(this.url, { headers: { Range: "bytes=0-0" } });
      const total = r.headers.get("Content-Range")?.split("/")[1];
      if (!r.ok || total === undefined) {
        throw new Error(`${this.url}: no range answer (${r.status})`);
      }
      this.length = BigInt(total);
    }
    return this.length;
  }

  async read(offset: bigint, size: bigint): Promise<Uint8Array> {
    if (size === 0n) {
      return new Uint8Array(0);
    }
    const r = await fetch(this.url, { headers: { Range: `bytes=${offset}-${offset + size - 1n}` } });
    if (r.status !== 206) {
      throw new Error(`${this.url}: range ${offset}+${size} answered ${r.status}`);
    }
    return new Uint8Array(await r.arrayBuffer());
  }
}

interface TelegramMessage {
  direction: "request" | "reply";
  kind: string;
  name: string;
  hex: string;
}

interface Series {
  times: bigint[];
}

/** The index of the last element <= x in a sorted array, -1 when none. */
export function lastAtOrBefore(sorted: bigint[], x: bigint): number {
  let lo = 0;
  let hi = sorted.length;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (sorted[mid] <= x) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo - 1;
}

const toNs = (t: number): bigint => BigInt(Math.round(t * 1e6)) * 1000n; // µs: a session's resolution
const toS = (ns: bigint): number => Number(ns / 1000n) / 1e6;
const decoder = new TextDecoder();

export class McapSource implements RecordingSource {
  private reader: McapIndexedReader | null = null;
  private replies = new Map<string, Series>();
  private summary: RecordingInfo | null = null;

  constructor(
    readonly url: string,
    readonly file: string,
  ) {}

  async info(): Promise<RecordingInfo> {
    if (this.summary !== null) {
      return this.summary;
    }
    const reader = await McapIndexedReader.Initialize({
      readable: new HttpReadable(this.url),
      decompressHandlers: { zstd: (buf, size) => decompress(buf, new Uint8Array(Number(size))) },
    });
    this.reader = reader;
    const events: RecordedEvent[] = [];
    let first: bigint | null = null;
    let last = 0n;
    for await (const m of reader.readMessages({ topics: [TELEGRAMS] })) {
      const body = JSON.parse(decoder.decode(m.data)) as TelegramMessage;
      first ??= m.logTime;
      last = m.logTime > last ? m.logTime : last;
      if (body.kind !== "frame") {
        continue;
      }
      if (body.direction === "reply") {
        let s = this.replies.get(body.name);
        if (s === undefined) {
          s = { times: [] };
          this.replies.set(body.name, s);
        }
        s.times.push(m.logTime);
      } else if (!body.name.startsWith("CMD_GET_")) {
        events.push({ t: toS(m.logTime), name: body.name });
      }
    }
    const start = first === null ? 0 : toS(first);
    this.summary = { kind: "mcap", file: this.file, start, end: first === null ? 0 : toS(last), events };
    return this.summary;
  }

  async stateAt(t: number): Promise<RecordedFrame[]> {
    const at = toNs(t) + 999n; // a session's times are rounded to the µs; the export's ns may lie just after
    const wanted = new Map<string, bigint>();
    for (const [name, s] of this.replies) {
      const i = lastAtOrBefore(s.times, at);
      if (i >= 0) {
        wanted.set(name, s.times[i]);
      }
    }
    const out: RecordedFrame[] = [];
    for (const [name, time] of wanted) {
      for (const f of await this.read(time, time)) {
        if (f.name === name && f.frame.dir === "reply") {
          out.push(f.frame);
        }
      }
    }
    return out.sort((a, b) => a.t - b.t);
  }

  async at(t: number, since: number, limit: number): Promise<RecordedState> {
    return { state: await this.stateAt(t), wire: await this.recordsIn(since, t, limit) };
  }

  async recordsIn(from: number, to: number, limit: number): Promise<RecordedFrame[]> {
    const frames = (await this.read(toNs(from) + 1000n, toNs(to) + 999n)).map((f) => f.frame);
    return frames.slice(-limit);
  }

  private async read(start: bigint, end: bigint): Promise<Array<{ name: string; frame: RecordedFrame }>> {
    const out: Array<{ name: string; frame: RecordedFrame }> = [];
    if (this.reader === null || end < start) {
      return out;
    }
    for await (const m of this.reader.readMessages({ topics: [TELEGRAMS], startTime: start, endTime: end })) {
      const body = JSON.parse(decoder.decode(m.data)) as TelegramMessage;
      if (body.kind === "frame") {
        out.push({ name: body.name, frame: { t: toS(m.logTime), dir: body.direction, hex: body.hex } });
      }
    }
    return out;
  }
}
