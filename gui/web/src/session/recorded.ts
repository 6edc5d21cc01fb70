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
 * - A name with no reply at or before t (a jump before the first status reply) shows nothing, as live before its
 *   first reply: the topic's last value is dropped, and without a status the session says it has none yet (not
 *   `connected`, a conn event: the status bar, the operation and motion panels show no status).
 * - Every seek publishes `seeked` (session.ts): the plotted replies up to t. A step forward of at most WIRE_BACK
 *   carries those among the wire's frames; a jump resets the plots and, once read (one more request, after the
 *   state is shown and HISTORY_AFTER_MS without another jump), carries the plots' window (PLOT_SPAN_S) before t.
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
  /** the plotted replies (GET_STATUS, GET_POSITION) with t - span < time <= t, at most `points` of each name */
  history(t: number, span: number, points: number): Promise<RecordedFrame[]>;
  /** the marks found after `info` (an MCAP file's commands are read in the background): all so far each time */
  onEvents?: (events: RecordedEvent[], complete: boolean) => void;
}

/** A jump longer than this shows the wire's last WIRE_BACK seconds before the new time rather than the gap. */
const WIRE_BACK = 1;
const WIRE_LIMIT = 100;
/** the plots' window (panels/plots.ts WINDOW_S) and how many points of each reply a jump's history holds */
const PLOT_SPAN_S = 60;
const PLOT_POINTS = 300;
/** a jump's history is asked for when no other jump came for this long */
const HISTORY_AFTER_MS = 250;
const PLOTTED = new Set(["CMD_GET_STATUS", "CMD_GET_POSITION"]);

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

  async history(t: number, span: number, points: number): Promise<RecordedFrame[]> {
    return (await json<{ frames: RecordedFrame[] }>(`${this.base}/history?t=${t}&span=${span}&points=${points}`))
      .frames;
  }
}

/** A hex digit's value by its character code (lower and upper case); 0 for any other character. */
const NIBBLE = new Uint8Array(128);
for (let d = 0; d < 16; d++) {
  NIBBLE["0123456789abcdef".charCodeAt(d)] = d;
  NIBBLE["0123456789ABCDEF".charCodeAt(d)] = d;
}

export function fromHex(hex: string): Uint8Array {
  const out = new Uint8Array(hex.length >> 1);
  for (let i = 0; i < out.length; i++) {
    out[i] = (NIBBLE[hex.charCodeAt(2 * i) & 127] << 4) | NIBBLE[hex.charCodeAt(2 * i + 1) & 127];
  }
  return out;
}

/** A reply's topic (the live session's dispatch, session.ts, kept beside it as a table): publish, and forget. */
interface Dispatch {
  publish(t: Telegram, s: RecordedSession): void;
  forget(s: RecordedSession): void;
}
function topic<T extends Telegram>(cls: new (...a: never[]) => T, of: (s: RecordedSession) => Topic<T>): Dispatch {
  return {
    publish: (t, s) => t instanceof cls && of(s).publish(t),
    forget: (s) => {
      of(s).last = undefined;
    },
  };
}
const TOPICS: Record<string, Dispatch> = {
  CMD_GET_STATUS: topic(GetStatusReply, (s) => s.status),
  CMD_GET_MAP: topic(GetMapReply, (s) => s.map),
  CMD_GET_ROADMAP: topic(GetRoadmapReply, (s) => s.roadmap),
  CMD_GET_DEBUG_DATA: topic(GetDebugDataReply, (s) => s.debug),
  CMD_GET_PLTF_PARAM_VEC: topic(GetPltfParamVecReply, (s) => s.params),
  CMD_GET_CAN_MESSAGES: topic(GetCanMessagesReply, (s) => s.can),
};

export class RecordedSession extends PlatformSession {
  /** the time shown (Unix s), published after the state at that time */
  readonly time = new Topic<number>();
  /** the timeline's marks, all so far (an MCAP file's arrive while it is shown), and whether that is all */
  readonly events = new Topic<{ events: RecordedEvent[]; complete: boolean }>();
  info: RecordingInfo | null = null;
  private shownAt = new Map<string, number>();
  private wanted: number | null = null;
  private reading: Promise<void> | null = null;
  private wireAt: number | null = null;
  private jumps = 0;

  constructor(readonly source: RecordingSource) {
    super("", "");
    this.fetchDocuments = false;
    source.onEvents = (events, complete) => this.events.publish({ events, complete });
  }

  /** Read the recording's times and events and show its first state. */
  async load(): Promise<RecordingInfo> {
    const info = await this.source.info();
    this.info = info;
    this.target = info.file;
    this.drive = { event: "control", holder: null, you: false, read_only: true, message: tr("timeline.readOnly") };
    this.driving.publish(this.drive);
    if (this.events.last === undefined) {
      this.events.publish({ events: info.events, complete: info.kind === "session" });
    }
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
      const step = this.wireAt !== null && this.wireAt < t && t - this.wireAt <= WIRE_BACK;
      const { state, wire } = await this.source.at(
        t,
        step && this.wireAt !== null ? this.wireAt : t - WIRE_BACK,
        WIRE_LIMIT,
      );
      this.wireAt = t;
      this.publishState(state);
      this.publishWire(wire);
      this.seeked.publish({ t, reset: !step, history: this.plotted(wire) });
      this.time.publish(t);
      if (!step) {
        void this.readHistory(t, ++this.jumps);
      }
    }
  }

  /** A jump's plots: the window before t, read after the state is shown; dropped when another jump came since. */
  private async readHistory(t: number, jump: number): Promise<void> {
    await new Promise((go) => setTimeout(go, HISTORY_AFTER_MS)); // a drag's jumps: only where it stops
    if (jump !== this.jumps) {
      return;
    }
    const frames = await this.source.history(t, PLOT_SPAN_S, PLOT_POINTS).catch(() => []);
    if (jump === this.jumps) {
      this.seeked.publish({ t, reset: true, history: this.plotted(frames), plotsOnly: true });
    }
  }

  private plotted(frames: RecordedFrame[]): Array<{ t: number; telegram: Telegram }> {
    const out = [];
    for (const f of frames) {
      const telegram = f.dir === "reply" ? this.decode(f) : null;
      if (telegram !== null && PLOTTED.has(telegram.telegramName)) {
        out.push({ t: f.t, telegram });
      }
    }
    return out;
  }

  private publishState(frames: RecordedFrame[]): void {
    const decoded = frames.map((f) => [f, this.decode(f)] as const);
    const names = new Set(decoded.map(([, t]) => t?.telegramName));
    this.forgetAbsent(names);
    this.setShowing(names.has("CMD_GET_STATUS"));
    for (const [f, telegram] of decoded) {
      if (telegram === null || this.shownAt.get(telegram.telegramName) === f.t) {
        continue;
      }
      this.shownAt.set(telegram.telegramName, f.t);
      TOPICS[telegram.telegramName]?.publish(telegram, this);
      this.replies.publish(telegram);
    }
  }

  /** The names shown before that have no reply at the new time: their topics keep no value (live before it). */
  private forgetAbsent(names: Set<string | undefined>): void {
    for (const name of [...this.shownAt.keys()]) {
      if (!names.has(name)) {
        this.shownAt.delete(name);
        TOPICS[name]?.forget(this);
      }
    }
  }

  /** With a status at the time shown the recording is "connected"; before its first one it has no status yet. */
  private setShowing(withStatus: boolean): void {
    if (withStatus === this.connected && this.conn.last !== undefined) {
      return;
    }
    this.connected = withStatus;
    const file = this.info?.file ?? "";
    const message = tr(withStatus ? "timeline.conn" : "timeline.noStatus", { file });
    this.conn.publish({ event: "recording", target: file, message });
  }

  private publishWire(frames: RecordedFrame[]): void {
    for (const f of frames) {
      const telegram = this.decode(f);
      if (telegram !== null) {
        const dir = f.dir === "request" ? "out" : "in";
        // ms from the whole µs the recording holds: f.t * 1000 can land an ulp below a whole ms (.925 shown .924)
        this.wire.publish({ dir, t: Math.round(f.t * 1e6) / 1000, telegram, bytes: f.hex.length / 2 });
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
