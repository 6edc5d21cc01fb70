/**
 * A recorded session (pltf gui --session FILE, issue 35): the data source that stands in for the platform, so the
 * panels do not know the difference (Foxglove's split). `RecordedSession` is a `PlatformSession` that publishes on
 * the same topics, the state at the scrubbed time, and sends nothing.
 *
 * Rules:
 * - `seek(t)` publishes the last reply of each telegram name at or before t (status, position, map, roadmap,
 *   debug data, CAN messages, parameters, ...) on the topics a live session publishes them on, and the frames
 *   since the last seek (a jump: the last seconds before t) on `wire`, as they passed. A reply already published
 *   is not published again (the map view redraws its static layer only when the map changes). Seeks are
 *   coalesced: while one is read, only the latest time asked for is read next.
 * - Where the frames come from is a `RecordingSource`: the gateway's index of a session file (`GatewaySource`,
 *   gui/recorded.py) or an MCAP file read in the page (`McapSource`, recorded_mcap.ts). Frames are bytes (`hex`,
 *   the truth of a recording: proxy/session.py) decoded here with the protocol's codec.
 * - Nothing is sent: `send` and `request` refuse with the reason, `mayCommand` is false (every command group is
 *   disabled: panels/control.ts), and the control line says "read-only".
 */
import { t as tr } from "../i18n/i18n";
import {
  decodeFrame,
  GetCanMessagesReply,
  GetDebugDataReply,
  GetMapReply,
  GetPltfParamVecReply,
  GetRoadmapReply,
  GetStatusReply,
  type Telegram,
} from "../pltf";
import { Topic } from "./bus";
import { PlatformSession } from "./session";

/** One frame of the recording: its time (Unix s), its direction and its bytes (hex). */
export interface RecordedFrame {
  t: number;
  dir: "request" | "reply";
  hex: string;
}

/** A request the application sent that is not a GET (guide 6.3: a command): a mark on the timeline. */
export interface RecordedEvent {
  t: number;
  name: string;
}

export interface RecordingInfo {
  kind: "session" | "mcap";
  file: string;
  start: number;
  end: number;
  events: RecordedEvent[];
}

/** What a seek shows: the last reply of each telegram name at or before t, and the wire's frames before it. */
export interface RecordedState {
  state: RecordedFrame[];
  /** the last `limit` frames with since < time <= t, in time order */
  wire: RecordedFrame[];
}

export interface RecordingSource {
  info(): Promise<RecordingInfo>;
  at(t: number, since: number, limit: number): Promise<RecordedState>;
}

/** A jump longer than this shows the wire's last WIRE_BACK seconds before the new time rather than the gap. */
const WIRE_BACK = 1;
const WIRE_LIMIT = 100;

async function json<T>(url: string): Promise<T> {
  const r = await fetch(url);
  if (!r.ok) {
    throw new Error(`${url}: ${r.status} ${await r.text()}`);
  }
  return (await r.json()) as T;
}

/** A session file indexed by the gateway (gui/recorded.py). */
export class GatewaySource implements RecordingSource {
  constructor(readonly base: string) {}

  info(): Promise<RecordingInfo> {
    return json<RecordingInfo>(this.base);
  }

  at(t: number, since: number, limit: number): Promise<RecordedState> {
    return json<RecordedState>(`${this.base}/state?t=${t}&since=${since}&limit=${limit}`);
  }
}

export function fromHex(hex: string): Uint8Array {
  const out = new Uint8Array(hex.length >> 1);
  for (let i = 0; i < out.length; i++) {
    out[i] = Number.parseInt(hex.substr(2 * i, 2), 16);
  }
  return out;
}

/** Publish a reply on its topic: the live session's dispatch (session.ts), kept beside it as a table. */
const TOPICS: Array<(t: Telegram, s: RecordedSession) => void> = [
  (t, s) => t instanceof GetStatusReply && s.status.publish(t),
  (t, s) => t instanceof GetMapReply && s.map.publish(t),
  (t, s) => t instanceof GetRoadmapReply && s.roadmap.publish(t),
  (t, s) => t instanceof GetDebugDataReply && s.debug.publish(t),
  (t, s) => t instanceof GetPltfParamVecReply && s.params.publish(t),
  (t, s) => t instanceof GetCanMessagesReply && s.can.publish(t),
];

export class RecordedSession extends PlatformSession {
  /** the time shown (Unix s), published after the state at that time */
  readonly time = new Topic<number>();
  info: RecordingInfo | null = null;
  private shownAt = new Map<string, number>();
  private wanted: number | null = null;
  private reading: Promise<void> | null = null;
  private wireAt: number | null = null;

  constructor(readonly source: RecordingSource) {
    super("", "");
    this.fetchDocuments = false;
  }

  /** Read the recording's times and events and show its first state. */
  async load(): Promise<RecordingInfo> {
    const info = await this.source.info();
    this.info = info;
    this.target = info.file;
    this.connected = true;
    this.drive = { event: "control", holder: null, you: false, read_only: true, message: tr("timeline.readOnly") };
    this.driving.publish(this.drive);
    this.conn.publish({ event: "recording", target: info.file, message: tr("timeline.conn", { file: info.file }) });
    await this.seek(info.start);
    return info;
  }

  /** Show the state at `t` (Unix s, clamped to the recording); resolves once it (or a later asked time) is shown. */
  seek(t: number): Promise<void> {
    const info = this.info;
    this.wanted = info === null ? t : Math.min(info.end, Math.max(info.start, t));
    if (this.reading === null) {
      this.reading = this.readWanted().finally(() => {
        this.reading = null;
      });
    }
    return this.reading;
  }

  private async readWanted(): Promise<void> {
    while (this.wanted !== null) {
      const t = this.wanted;
      this.wanted = null;
      const back =
        this.wireAt !== null && this.wireAt < t && t - this.wireAt <= WIRE_BACK ? this.wireAt : t - WIRE_BACK;
      const { state, wire } = await this.source.at(t, back, WIRE_LIMIT);
      this.wireAt = t;
      this.publishState(state);
      this.publishWire(wire);
      this.time.publish(t);
    }
  }

  private publishState(frames: RecordedFrame[]): void {
    for (const f of frames) {
      const telegram = this.decode(f);
      if (telegram === null || this.shownAt.get(telegram.telegramName) === f.t) {
        continue;
      }
      this.shownAt.set(telegram.telegramName, f.t);
      for (const publish of TOPICS) {
        publish(telegram, this);
      }
      this.replies.publish(telegram);
    }
  }

  private publishWire(frames: RecordedFrame[]): void {
    for (const f of frames) {
      const telegram = this.decode(f);
      if (telegram !== null) {
        const dir = f.dir === "request" ? "out" : "in";
        this.wire.publish({ dir, t: f.t * 1000, telegram, bytes: f.hex.length / 2 });
      }
    }
  }

  private decode(f: RecordedFrame): Telegram | null {
    try {
      return decodeFrame(fromHex(f.hex), f.dir);
    } catch {
      return null; // a malformed frame of the recording: the wire inspector of a live session drops it too
    }
  }

  override get mayCommand(): boolean {
    return false;
  }

  override open(): void {}

  override close(): void {}

  override watchTruth(): void {}

  override takeControl(): void {}

  override askStats(): void {}

  override setPolling(): void {}

  override send(t: Telegram): void {
    throw new Error(`${t.telegramName} ${tr("timeline.notSent")}`);
  }

  override request<T extends Telegram>(t: Telegram): Promise<T> {
    return Promise.reject(new Error(`${t.telegramName} ${tr("timeline.notSent")}`));
  }
}
