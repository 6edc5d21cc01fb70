/**
 * The platform session: the only module that talks to the gateway. It owns the WebSocket, the requests in
 * flight and the polling, and publishes every decoded telegram on topics; panels subscribe and send through it.
 *
 * Rules:
 * - One binary WebSocket message is one frame, either direction; text messages are the gateway's JSON events.
 * - guide 6.1: only the answered telegrams (spec ANSWERED) get a reply; their promises are kept in a FIFO,
 *   since the gateway hands this tab its replies in the order of its requests.
 * - Polling: each poller has at most one request in flight and asks again one period after the last reply.
 *   GET_STATUS runs at DEFAULT_STATUS_HZ while connected; the others are switched on by the panels that need them.
 * - A lost gateway is reconnected with backoff and said so; every failure ends up as a "conn" event in words.
 * - Who drives (gui/control.py, issue 33): the gateway tells each tab who holds control ("control" events). A tab
 *   that may not command (another tab drives, or the gateway is read-only) sends no command: `send` refuses the
 *   telegrams the platform does not answer (guide 6.1), and the gateway refuses them too. A target that is not on
 *   the gateway's list ("target_refused") is said and not tried again.
 */
import { ANSWERED } from "../spec";
import {
  decodeFrame,
  encode,
  GetCanMessagesReply,
  GetDebugDataReply,
  GetMapReply,
  GetPltfParamVecReply,
  GetRoadmapReply,
  GetStatusReply,
  GetStatusRequest,
  GetMapRequest,
  GetRoadmapRequest,
  type ProtocolError,
  type Telegram,
} from "../pltf";
import { Topic } from "./bus";
import type { EditedDocument } from "./edited";
import { t as tr } from "../i18n/i18n";

export const DEFAULT_STATUS_HZ = 20;

export interface ConnEvent {
  event: string;
  message: string;
  target: string;
  [key: string]: unknown;
}

/** gui/truth.py: the true pose and the injected faults, or why the control channel cannot be read. */
export interface TruthEvent {
  event: "truth" | "truth_lost";
  control: string;
  true?: [number, number, number]; // mm, mm, degrees
  faults?: Array<{ kind: string; target: string; value?: number | string | null }>;
  detail?: string;
}

/** gui/control.py: who holds control of this target. */
export interface ControlEvent {
  event: "control";
  holder: string | null;
  you: boolean;
  read_only: boolean;
  message: string;
}

/** A recording's seek (session/recorded.ts; a live session never publishes it): the time shown (Unix s) and the
 * plotted replies (GET_STATUS, GET_POSITION) up to it; `reset`: what was drawn before is not the past of `t`.
 * It comes after the seek's replies and wire records: a topic without a value then (`last` undefined) has no reply
 * at `t`, and a panel shows nothing for it; on a reset the wire's records since the previous seek are all of t's. */
export interface Seeked {
  t: number;
  reset: boolean;
  history: Array<{ t: number; telegram: Telegram }>;
  /** the plots' window of a jump, read after it (session/recorded.ts): nothing else changed, the other panels keep
   * what they show */
  plotsOnly?: boolean;
}

export interface WireRecord {
  dir: "out" | "in";
  t: number;
  telegram: Telegram;
  bytes: number;
}

interface Waiting {
  id: number;
  name: string;
  resolve: (t: Telegram) => void;
  reject: (e: Error) => void;
}

class Poller {
  timer: number | null = null;
  busy = false;
  constructor(
    readonly session: PlatformSession,
    readonly make: () => Telegram,
    public hz: number,
  ) {}

  start(): void {
    if (this.timer === null && !this.busy) {
      this.tick();
    }
  }

  stop(): void {
    if (this.timer !== null) {
      clearTimeout(this.timer);
      this.timer = null;
    }
  }

  private tick(): void {
    this.timer = null;
    if (!this.session.connected) {
      return;
    }
    this.busy = true;
    const t0 = performance.now();
    this.session
      .request(this.make())
      .catch(() => undefined)
      .finally(() => {
        this.busy = false;
        if (this.session.connected && this.active) {
          const wait = Math.max(0, 1000 / this.hz - (performance.now() - t0));
          this.timer = window.setTimeout(() => this.tick(), wait);
        }
      });
  }

  active = false;
}

export class PlatformSession {
  readonly conn = new Topic<ConnEvent>();
  readonly status = new Topic<GetStatusReply>();
  readonly map = new Topic<GetMapReply>();
  readonly roadmap = new Topic<GetRoadmapReply>();
  readonly debug = new Topic<GetDebugDataReply>();
  readonly params = new Topic<GetPltfParamVecReply>();
  readonly can = new Topic<GetCanMessagesReply>();
  readonly replies = new Topic<Telegram>();
  readonly wire = new Topic<WireRecord>();
  readonly seeked = new Topic<Seeked>();
  readonly gatewayStats = new Topic<Record<string, unknown>>();
  /** The optional ground truth from the reference server's control channel (gui/truth.py): never needed. */
  readonly truth = new Topic<TruthEvent>();
  private control: string | null = null;
  /** Who drives (gui/control.py); `drive` is the last word. */
  readonly driving = new Topic<ControlEvent>();
  drive: ControlEvent | null = null;
  /** The gateway refused this target (not on its list): not tried again until another target is opened. */
  private refusedTarget = false;
  /** Events about single requests (not sent, refused by the gateway): shown, but not the connection's state. */
  readonly notices = new Topic<ConnEvent>();
  /** The document an open editor shows on the map view (editor/*panel.ts publish, panels/mapview.ts draws). */
  readonly edited = new Topic<EditedDocument | null>();
  /** This tab's own traffic (TCP Client tab). */
  readonly traffic = {
    bytesOut: 0,
    bytesIn: 0,
    telegramsOut: 0,
    telegramsIn: 0,
    errors: 0,
    reconnects: 0,
    rtt: [] as number[],
  };

  connected = false;
  /** GET_MAP and GET_ROADMAP on connecting; false for a fleet's watched platforms (panels/fleet.ts: status only) */
  fetchDocuments = true;
  private ws: WebSocket | null = null;
  private waiting: Waiting[] = [];
  private sentAt: number[] = [];
  private pollers = new Map<string, Poller>();
  private wantOpen = false;
  private wsRetry = 0;

  constructor(
    readonly url: string,
    public target: string,
  ) {
    this.poll("status", () => new GetStatusRequest(), DEFAULT_STATUS_HZ);
  }

  /** Open Socket (guide 5.2): connect the gateway's link to the platform. */
  open(target?: string): void {
    if (target !== undefined && target !== this.target) {
      this.detach();
      this.target = target;
      this.refusedTarget = false;
    }
    this.wantOpen = true;
    if (this.ws === null) {
      this.attach();
    } else if (this.ws.readyState === WebSocket.OPEN) {
      this.ws.send(JSON.stringify({ op: "open" }));
    }
  }

  /** Close Socket (guide 5.2): CMD_CLOSE_SOCKET, then the link closes; the operating mode stays. */
  close(farewell?: Telegram): void {
    this.wantOpen = false;
    if (farewell !== undefined && this.connected && this.mayCommand) {
      this.send(farewell);
    }
    this.setConnected(false);
    if (this.ws?.readyState === WebSocket.OPEN) {
      this.ws.send(JSON.stringify({ op: "close" }));
    }
  }

  /** Read the ground truth from a reference server's control channel (HOST:PORT, loopback); "" stops it. */
  watchTruth(control: string): void {
    this.control = control === "" ? null : control;
    if (this.control !== null && this.ws?.readyState === WebSocket.OPEN) {
      this.ws.send(JSON.stringify({ op: "truth", control: this.control }));
    }
  }

  /** May this tab send a command now: the gateway is not read-only and nobody else drives. */
  get mayCommand(): boolean {
    const d = this.drive;
    return d === null || (!d.read_only && (d.holder === null || d.you));
  }

  /** Take control (an explicit action: the tab that drove becomes a viewer). */
  takeControl(): void {
    if (this.ws?.readyState === WebSocket.OPEN) {
      this.ws.send(JSON.stringify({ op: "take" }));
    }
  }

  askStats(): void {
    if (this.ws?.readyState === WebSocket.OPEN) {
      this.ws.send(JSON.stringify({ op: "stats" }));
    }
  }

  private attach(): void {
    const ws = new WebSocket(`${this.url}?target=${encodeURIComponent(this.target)}`);
    ws.binaryType = "arraybuffer";
    this.ws = ws;
    ws.onopen = () => {
      this.wsRetry = 0;
      if (this.control !== null) {
        ws.send(JSON.stringify({ op: "truth", control: this.control }));
      }
      if (this.wantOpen) {
        ws.send(JSON.stringify({ op: "open" }));
      }
    };
    ws.onmessage = (ev: MessageEvent) => {
      if (this.ws !== ws) {
        return; // a socket left at a switch: its platform's replies are not this target's
      }
      if (typeof ev.data === "string") {
        this.onEvent(JSON.parse(ev.data) as ConnEvent);
      } else {
        this.onFrame(new Uint8Array(ev.data as ArrayBuffer));
      }
    };
    ws.onclose = () => {
      if (this.ws !== ws) {
        return;
      }
      this.ws = null;
      this.setConnected(false);
      if (this.refusedTarget) {
        return; // said once (target_refused); trying again would be refused again
      }
      this.failAll("the gateway connection was lost");
      const delay = Math.min(8000, 500 * 2 ** this.wsRetry++);
      this.conn.publish({
        event: "gateway_lost",
        target: this.target,
        message: `lost the connection to the GUI gateway; retrying in ${delay / 1000} s`,
        delay: delay / 1000,
      });
      window.setTimeout(() => {
        if (this.ws === null) {
          this.attach();
        }
      }, delay);
    };
  }

  private detach(): void {
    const ws = this.ws;
    this.ws = null;
    this.setConnected(false);
    this.drive = null;
    this.failAll("switched to another platform");
    ws?.close();
  }

  private onEvent(ev: ConnEvent): void {
    if (ev.event === "stats") {
      this.gatewayStats.publish(ev);
      return;
    }
    if (ev.event === "truth" || ev.event === "truth_lost") {
      this.truth.publish(ev as unknown as TruthEvent);
      return;
    }
    if (ev.event === "control") {
      this.drive = ev as unknown as ControlEvent;
      this.driving.publish(this.drive);
      return;
    }
    if (ev.event === "target_refused") {
      this.refusedTarget = true;
    }
    if (
      ev.event === "lost" ||
      ev.event === "not_sent" ||
      ev.event === "bad_request" ||
      ev.event === "refused_command"
    ) {
      const id = ev.id as number | undefined;
      if (id !== undefined && this.waiting.length > 0 && this.waiting[0].id === id) {
        this.waiting.shift()!.reject(new Error(ev.message));
        this.sentAt.shift();
      }
      if (ev.event !== "lost") {
        this.traffic.errors++;
        this.notices.publish(ev);
      }
      return;
    }
    if (ev.event === "connected") {
      this.setConnected(true);
    } else if (
      [
        "closed",
        "connecting",
        "retry",
        "refused",
        "unreachable",
        "turned_away",
        "dropped",
        "timeout",
        "malformed",
      ].includes(ev.event)
    ) {
      if (ev.event !== "closed" && ev.event !== "connecting" && ev.event !== "retry") {
        this.traffic.errors++;
      }
      if (ev.event === "retry") {
        this.traffic.reconnects++;
      }
      this.setConnected(false);
      this.failAll(ev.message);
    }
    this.conn.publish(ev);
  }

  private setConnected(up: boolean): void {
    if (up === this.connected) {
      return;
    }
    this.connected = up;
    for (const p of this.pollers.values()) {
      if (up && p.active) {
        p.start();
      } else {
        p.stop();
      }
    }
    if (up && this.fetchDocuments) {
      this.refreshDocuments();
    } else {
      this.status.last = undefined; // no stale readings after a reconnect
    }
  }

  /** Refresh map (guide 5.3): GET_MAP and GET_ROADMAP. */
  refreshDocuments(): void {
    this.request(new GetMapRequest()).catch(() => undefined);
    this.request(new GetRoadmapRequest()).catch(() => undefined);
  }

  private failAll(why: string): void {
    const waiting = this.waiting;
    this.waiting = [];
    this.sentAt = [];
    for (const w of waiting) {
      w.reject(new Error(`${w.name}: ${why}`));
    }
  }

  private onFrame(bytes: Uint8Array): void {
    this.traffic.bytesIn += bytes.length;
    this.traffic.telegramsIn++;
    let telegram: Telegram;
    try {
      telegram = decodeFrame(bytes, "reply");
    } catch (e) {
      this.traffic.errors++;
      const detail = (e as ProtocolError).message;
      this.conn.publish({ event: "malformed", target: this.target, message: `a malformed reply: ${detail}`, detail });
      return;
    }
    const head = this.waiting.shift();
    const t0 = this.sentAt.shift();
    if (t0 !== undefined) {
      this.traffic.rtt.push(performance.now() - t0);
      if (this.traffic.rtt.length > 200) {
        this.traffic.rtt.splice(0, this.traffic.rtt.length - 200);
      }
    }
    this.wire.publish({ dir: "in", t: Date.now(), telegram, bytes: bytes.length });
    this.dispatch(telegram);
    if (head !== undefined) {
      if (head.id === telegram.telegramId) {
        head.resolve(telegram);
      } else {
        head.reject(new Error(`${head.name}: got a ${telegram.telegramName} reply instead`));
      }
    }
  }

  private dispatch(t: Telegram): void {
    if (t instanceof GetStatusReply) {
      this.status.publish(t);
    } else if (t instanceof GetMapReply) {
      this.map.publish(t);
    } else if (t instanceof GetRoadmapReply) {
      this.roadmap.publish(t);
    } else if (t instanceof GetDebugDataReply) {
      this.debug.publish(t);
    } else if (t instanceof GetPltfParamVecReply) {
      this.params.publish(t);
    } else if (t instanceof GetCanMessagesReply) {
      this.can.publish(t);
    }
    this.replies.publish(t);
  }

  /** Send a telegram that gets no reply (guide 6.1); throws the codec's error for a bad field. */
  send(t: Telegram): void {
    const bytes = encode(t);
    if (this.ws?.readyState !== WebSocket.OPEN || !this.connected) {
      throw new Error(`${t.telegramName} not sent: the socket is not open`);
    }
    if (!this.mayCommand && !ANSWERED.has(t.telegramId)) {
      throw new Error(
        `${t.telegramName} ${this.drive?.read_only ? tr("control.refusedReadOnly") : tr("control.refusedViewer", { holder: this.drive?.holder ?? "" })}`,
      );
    }
    this.ws.send(bytes);
    this.traffic.bytesOut += bytes.length;
    this.traffic.telegramsOut++;
    this.wire.publish({ dir: "out", t: Date.now(), telegram: t, bytes: bytes.length });
  }

  /** Send a request and wait for its reply (GET_*), or resolve at once with null when it gets none. */
  request<T extends Telegram>(t: Telegram): Promise<T> {
    const answered = ANSWERED.has(t.telegramId);
    try {
      this.send(t);
    } catch (e) {
      return Promise.reject(e);
    }
    if (!answered) {
      return Promise.resolve(null as unknown as T);
    }
    return new Promise<T>((resolve, reject) => {
      this.waiting.push({ id: t.telegramId, name: t.telegramName, resolve: resolve as (t: Telegram) => void, reject });
      this.sentAt.push(performance.now());
    });
  }

  /** A poller: `make()` every 1/hz s while `active` and connected. */
  poll(name: string, make: () => Telegram, hz: number): Poller {
    let p = this.pollers.get(name);
    if (p === undefined) {
      p = new Poller(this, make, hz);
      p.active = name === "status";
      this.pollers.set(name, p);
    }
    return p;
  }

  setPolling(name: string, on: boolean, hz?: number): void {
    const p = this.pollers.get(name);
    if (p === undefined) {
      return;
    }
    if (hz !== undefined) {
      p.hz = hz;
    }
    p.active = on;
    if (on && this.connected) {
      p.start();
    } else if (!on) {
      p.stop();
    }
  }
}
