/**
 * An MCAP recording read in the page (pltf gui --session FILE.mcap, issue 35), as Foxglove reads one: @mcap/core's
 * McapIndexedReader over HTTP range requests (the gateway serves the file: GET /recording.mcap), its chunks
 * decompressed by mcap_decompress.ts's handlers (zstd, lz4, or none: every `pltf export --compression`) and kept
 * between seeks (mcap_cache.ts: an LRU by offset). The frames are the raw telegrams' channel of `pltf export
 * --mcap` (proxy/mcap_export.py: /pltf/telegrams, one JSON message per frame with its direction, name and hex); the
 * other channels are for Foxglove.
 *
 * Rules (an hour's export is ~300 MB in ~600 chunks of ~18 s each: opening and seeking read a few of them, never
 * the whole file; decompressing a 4 MiB chunk with zstd is most of a seek's cost):
 * - Opening reads the summary (chunk indexes, statistics) and the first and the last message of the telegrams'
 *   channel (its first and last chunk): the recording's start and end.
 * - A seek to t reads the telegrams before t backwards, LOOKBACK_S at most and no further back than the start of
 *   the chunk holding t (but always the wire's window, `since`), and keeps the last reply of each name: one chunk
 *   for most seeks (erratum E-GUI-011). A status, position, map or roadmap not among them is looked for on the
 *   channel of its own (OWN: the status on /scan, the position on /pose, the map and the roadmap on /map; a channel
 *   without messages in the file's statistics is skipped), backwards in widening windows, so only chunks holding
 *   that channel are read; its telegram is then read at that time. Other names (parameters, CAN messages, debug
 *   data, commands' replies) older than that come from the background read below, once it has passed t (before
 *   that they are not shown: E-GUI-011; the session file has no such gap).
 * - The marks (the commands) and those other names' times come from a background read of the telegrams' channel,
 *   SCAN_SLICE_S of recording at a time, in time order, when no seek came for SCAN_IDLE_MS (seeks first); the marks
 *   are handed on (`onEvents`) after each slice.
 * - A message's JSON is not parsed: its direction, kind and name are read from its head (the export writes them
 *   before the hex, in that order) and its hex only when a frame is shown; a message of another layout is parsed.
 *   Chunks' CRCs are not checked (their size is: mcap_decompress.ts); a damaged frame fails to decode and is
 *   dropped, as a malformed one.
 * - Times are the messages' log times (ns).
 */
import { McapIndexedReader } from "@mcap/core";
import type { IReadable } from "@mcap/core";
import { ChunkCache } from "./mcap_cache";
import { decompressHandlers } from "./mcap_decompress";
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

/** The head of a pltf.Telegram message as the export writes it, up to the hex's first digit. */
const HEAD = /"direction":"(request|reply)","kind":"([^"]*)","name":"([^"]*)","hex":"/;
const HEAD_BYTES = 320;
const QUOTE = 0x22;

/** A telegram message's frame (null: not a frame), its hex read from `data` only when asked for. */
export function telegramFrame(t: number, data: Uint8Array): Found | null {
  const head = HEAD.exec(decoder.decode(data.subarray(0, HEAD_BYTES)));
  const start = head === null ? -1 : head.index + head[0].length;
  if (head === null || data[start - 1] !== QUOTE || data[start - 7] !== QUOTE) {
    const body = JSON.parse(decoder.decode(data)) as TelegramMessage; // another writer's layout (or a non-ASCII head)
    return body.kind === "frame" ? { name: body.name, frame: { t, dir: body.direction, hex: body.hex } } : null;
  }
  if (head[2] !== "frame") {
    return null;
  }
  let hex: string | undefined;
  const frame = {
    t,
    dir: head[1] as "request" | "reply",
    get hex(): string {
      hex ??= decoder.decode(data.subarray(start, data.indexOf(QUOTE, start)));
      return hex;
    },
  };
  return { name: head[3], frame };
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
/** s from ns, through the whole µs nearest (as recorded.ts and the session file's reader take them): cut to the µs
 * below, a frame at .9049995 s showed at .904 where its recording's session file says .905 (hog run 36) */
const toS = (ns: bigint): number => Number((ns + 500n) / 1000n) / 1e6;
const decoder = new TextDecoder();

const LOOKBACK_S = 5;
const SCAN_SLICE_S = 10;
/** the background read waits until no seek came for this long (a drag of the scrubber goes first) */
const SCAN_IDLE_MS = 400;
const S_NS = 1_000_000_000n;
/** The replies with a channel of their own (proxy/mcap_export.py), and how to know one of that name there. */
const OWN: Record<string, { topic: string; entity?: string }> = {
  CMD_GET_STATUS: { topic: "/scan" },
  CMD_GET_POSITION: { topic: "/pose" },
  CMD_GET_MAP: { topic: "/map", entity: "map" },
  CMD_GET_ROADMAP: { topic: "/map", entity: "roadmap" },
};
const ENTITY = /"id":"([^"]*)"/;

export interface Found {
  name: string;
  frame: RecordedFrame;
}

export class McapSource implements RecordingSource {
  private reader: McapIndexedReader | null = null;
  private summary: RecordingInfo | null = null;
  private startNs = 0n;
  private endNs = 0n;
  /** the start times of the telegrams' chunks, in order; the channels with messages (the file's statistics) */
  private chunkStarts: bigint[] = [];
  private hasMessages: (topic: string) => boolean = () => true;
  cache: ChunkCache | null = null;
  /** the background read: the other names' reply times, the marks, how far it has come (ns) */
  private replies = new Map<string, bigint[]>();
  private events: RecordedEvent[] = [];
  private scannedTo = -1n;
  private seeking = 0;
  private lastSeek = 0;
  private resume: Array<() => void> = [];
  onEvents?: (events: RecordedEvent[], complete: boolean) => void;

  constructor(
    readonly url: string,
    readonly file: string,
  ) {}

  async info(): Promise<RecordingInfo> {
    if (this.summary !== null) {
      return this.summary;
    }
    const cache = new ChunkCache(new HttpReadable(this.url));
    this.cache = cache;
    const reader = await McapIndexedReader.Initialize({
      readable: cache,
      decompressHandlers: cache.decompressing(decompressHandlers),
    });
    this.reader = reader;
    const ids = new Set([...reader.channelsById.values()].filter((c) => c.topic === TELEGRAMS).map((c) => c.id));
    const chunks = reader.chunkIndexes.filter((c) => [...c.messageIndexOffsets.keys()].some((id) => ids.has(id)));
    this.chunkStarts = chunks.map((c) => c.messageStartTime).sort((a, b) => (a < b ? -1 : a > b ? 1 : 0));
    const counts = reader.statistics?.channelMessageCounts;
    if (counts !== undefined) {
      const topics = new Set(
        [...reader.channelsById].filter(([id]) => (counts.get(id) ?? 0n) > 0n).map(([, c]) => c.topic),
      );
      this.hasMessages = (topic) => topics.has(topic);
    }
    if (chunks.length > 0) {
      const first = chunks.reduce((a, b) => (b.messageStartTime < a.messageStartTime ? b : a));
      const last = chunks.reduce((a, b) => (b.messageEndTime > a.messageEndTime ? b : a));
      this.startNs = (await this.first(TELEGRAMS, first.messageStartTime, first.messageEndTime, false)) ?? 0n;
      this.endNs = (await this.first(TELEGRAMS, last.messageStartTime, last.messageEndTime, true)) ?? this.startNs;
    }
    this.summary = { kind: "mcap", file: this.file, start: toS(this.startNs), end: toS(this.endNs), events: [] };
    void this.scan();
    return this.summary;
  }

  /** The log time of the first message of `topic` in [a, b] (the last one: `reverse`), null when none. */
  private async first(topic: string, a: bigint, b: bigint, reverse: boolean): Promise<bigint | null> {
    const args = { topics: [topic], startTime: a, endTime: b, reverse, validateCrcs: false };
    for await (const m of this.reader!.readMessages(args)) {
      return m.logTime;
    }
    return null;
  }

  /** One read backwards from t serves the state's lookback and the wire's frames since `since`. */
  async at(t: number, since: number, limit: number): Promise<RecordedState> {
    this.seeking++;
    this.lastSeek = performance.now();
    try {
      const at = toNs(t) + 999n; // a session's times are rounded to the µs; the export's ns may lie just after
      const from = toNs(since) + 1000n;
      const back = this.lookback(at, from);
      const recent = await this.read(back, at, true);
      const wire = recent
        .filter((f) => toNs(f.frame.t) >= from)
        .slice(0, limit)
        .reverse();
      const state = await this.stateAt(at, back, recent);
      return { state, wire: wire.map((f) => f.frame) };
    } finally {
      this.lastSeek = performance.now();
      if (--this.seeking === 0) {
        this.resume.splice(0).forEach((go) => go());
      }
    }
  }

  /** Where a seek's backwards read stops (E-GUI-011): LOOKBACK_S before `at`, but not before the start of the
   * chunk holding `at`, unless the wire's window (`from`) reaches further. */
  lookback(at: bigint, from: bigint): bigint {
    const i = lastAtOrBefore(this.chunkStarts, at);
    const chunk = i < 0 ? this.startNs : this.chunkStarts[i];
    const lookback = at - BigInt(LOOKBACK_S) * S_NS;
    const stop = chunk < from ? chunk : from;
    return stop > lookback ? stop : lookback;
  }

  /** The state at `at` (ns) from `recent`, the telegrams since `back` newest first, and the channels. */
  private async stateAt(at: bigint, back: bigint, recent: Found[]): Promise<RecordedFrame[]> {
    const found = new Map<string, RecordedFrame>();
    for (const f of recent) {
      if (f.frame.dir === "reply" && !found.has(f.name)) {
        found.set(f.name, f.frame);
      }
    }
    for (const [name, own] of Object.entries(OWN)) {
      if (!found.has(name) && this.hasMessages(own.topic)) {
        const when = await this.lastOn(own.topic, back, own.entity);
        const frame = when === null ? undefined : await this.replyAt(name, when);
        if (frame !== undefined) {
          found.set(name, frame);
        }
      }
    }
    if (this.scannedTo >= at) {
      for (const [name, times] of this.replies) {
        const i = lastAtOrBefore(times, at);
        const frame = i < 0 || found.has(name) ? undefined : await this.replyAt(name, times[i]);
        if (frame !== undefined) {
          found.set(name, frame);
        }
      }
    }
    return [...found.values()].sort((a, b) => a.t - b.t);
  }

  /** The log time of the last message of `topic` (of that entity) before `before`, in windows that widen
   * backwards: only the chunks of the window that hold the channel are read. */
  private async lastOn(topic: string, before: bigint, entity?: string): Promise<bigint | null> {
    let width = BigInt(LOOKBACK_S) * S_NS;
    for (let end = before; end >= this.startNs; width *= 4n) {
      const start = end - width;
      for await (const m of this.reader!.readMessages({
        topics: [topic],
        startTime: start,
        endTime: end,
        reverse: true,
        validateCrcs: false,
      })) {
        if (entity === undefined || ENTITY.exec(decoder.decode(m.data.subarray(0, 400)))?.[1] === entity) {
          return m.logTime;
        }
      }
      end = start - 1n;
    }
    return null;
  }

  private async replyAt(name: string, time: bigint): Promise<RecordedFrame | undefined> {
    const frames = await this.read(time - 1_000_000n, time, true);
    return frames.find((f) => f.name === name && f.frame.dir === "reply")?.frame;
  }

  async recordsIn(from: number, to: number, limit: number): Promise<RecordedFrame[]> {
    const frames = (await this.read(toNs(from) + 1000n, toNs(to) + 999n)).map((f) => f.frame);
    return frames.slice(-limit);
  }

  async history(t: number, span: number, points: number): Promise<RecordedFrame[]> {
    const frames = await this.read(toNs(t - span) + 1000n, toNs(t) + 999n);
    const out: RecordedFrame[] = [];
    for (const name of Object.keys(OWN).slice(0, 2)) {
      const mine = frames.filter((f) => f.name === name && f.frame.dir === "reply").map((f) => f.frame);
      out.push(...spread(mine, points));
    }
    return out.sort((a, b) => a.t - b.t);
  }

  /** The background read: marks and the other names' reply times, a slice at a time, seeks first. */
  private async scan(): Promise<void> {
    const slice = BigInt(SCAN_SLICE_S) * S_NS;
    for (let a = this.startNs; a <= this.endNs; a += slice) {
      while (this.seeking > 0 || performance.now() - this.lastSeek < SCAN_IDLE_MS) {
        if (this.seeking > 0) {
          await new Promise<void>((go) => this.resume.push(go));
        } else {
          await new Promise((go) => setTimeout(go, SCAN_IDLE_MS));
        }
      }
      const b = a + slice - 1n;
      for (const f of await this.read(a, b)) {
        if (f.frame.dir === "request" && !f.name.startsWith("CMD_GET_")) {
          this.events.push({ t: f.frame.t, name: f.name });
        } else if (f.frame.dir === "reply" && !(f.name in OWN)) {
          let times = this.replies.get(f.name);
          if (times === undefined) {
            times = [];
            this.replies.set(f.name, times);
          }
          times.push(toNs(f.frame.t));
        }
      }
      this.scannedTo = b;
      this.onEvents?.(this.events, b >= this.endNs);
      await new Promise((go) => setTimeout(go, 0));
    }
  }

  private async read(start: bigint, end: bigint, reverse = false): Promise<Found[]> {
    const out: Found[] = [];
    if (this.reader === null || end < start) {
      return out;
    }
    const args = { topics: [TELEGRAMS], startTime: start, endTime: end, reverse, validateCrcs: false };
    for await (const m of this.reader.readMessages(args)) {
      const found = telegramFrame(toS(m.logTime), m.data);
      if (found !== null) {
        out.push(found);
      }
    }
    return out;
  }
}

/** At most `n` of `xs`, evenly spread, the last always among them (gui/recorded.py `spread`). */
export function spread<T>(xs: T[], n: number): T[] {
  if (xs.length <= n) {
    return xs;
  }
  const picked = new Set<number>();
  for (let k = 0; k < n; k++) {
    picked.add(xs.length - 1 - Math.floor((k * (xs.length - 1)) / Math.max(1, n - 1)));
  }
  return [...picked].sort((a, b) => a - b).map((i) => xs[i]);
}
