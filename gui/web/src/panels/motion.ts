/**
 * The controls of each motion mode (guide 4.3, 5.6), shown for the mode the platform reports:
 * - Velocity and Joystick (Software): CMD_MOVE_VEL from the arrow keys (or W A S D) or the on-screen joystick,
 *   re-sent every RESEND_MS while held (guide 4.3: "keeps the last set velocity until a new velocity value is set
 *   or a watchdog time expired"; VelWatchdogTime defaults to 500 ms) and a zero velocity on release.
 * - Automatic: the target flag (map view), the target station (CMD_MOVE_TO_STATION), CMD_MOVE_ABS, CMD_MOVE_REL.
 * - Post-process replay: the record and replay events (CMD_SET_EVENT).
 * - Joystick (Hardware), Program, No Motion: what the mode means; nothing to send.
 */
import { field, h } from "../dom";
import { bind, type Key, onLanguage, t } from "../i18n/i18n";
import {
  Event,
  type GetStatusReply,
  MotionMode,
  MoveAbsRequest,
  MoveRelRequest,
  MoveToStationRequest,
  MoveVelRequest,
  OperationState,
  SetEventRequest,
  type Telegram,
} from "../pltf";
import { parseRoadmap } from "../scene/roadmap";
import type { PlatformSession } from "../session/session";
import { commands } from "./control";
import type { MapView } from "./mapview";

export const RESEND_MS = 100;
const KEYS: Record<string, [number, number]> = {
  ArrowUp: [1, 0],
  w: [1, 0],
  ArrowDown: [-1, 0],
  s: [-1, 0],
  ArrowLeft: [0, 1],
  a: [0, 1],
  ArrowRight: [0, -1],
  d: [0, -1],
};

function numberInput(value: number, attrs: Record<string, string> = {}): HTMLInputElement {
  const input = h("input", { type: "number", value: String(value), step: "any", ...attrs });
  return input;
}

export function motionPanel(session: PlatformSession, map: MapView, say: (text: string) => void): HTMLElement {
  const root = h("section", { class: "motion" });
  bind(root, "motion.controls", { text: false });
  let status: GetStatusReply | null = null;
  const send = (tg: Telegram, key?: Key) => {
    try {
      session.send(tg);
      if (key) {
        say(t(key));
      }
    } catch (e) {
      say((e as Error).message);
    }
  };
  const btn = (key: Key, fn: () => void) => {
    const b = h("button", { type: "button" });
    bind(b, key);
    b.addEventListener("click", fn);
    return b;
  };

  // ---- velocity: keys and joystick
  const vTrans = numberInput(300, { min: "0", max: "3000" });
  const vRot = numberInput(500, { min: "0", max: "6000" });
  const held = new Map<string, [number, number]>();
  let joy: [number, number] | null = null;
  let timer: number | null = null;
  const velocityMode = () =>
    status !== null &&
    (status.motionMode === MotionMode.MODE_MOTION_VEL || status.motionMode === MotionMode.MODE_MOTION_JOYSOFT);
  const command = (): [number, number] => {
    let f = 0;
    let r = 0;
    for (const [a, b] of held.values()) {
      f += a;
      r += b;
    }
    if (joy !== null) {
      [f, r] = joy;
    }
    f = Math.max(-1, Math.min(1, f));
    r = Math.max(-1, Math.min(1, r));
    return [Math.round(f * Number(vTrans.value)), Math.round(r * Number(vRot.value))];
  };
  const drive = () => {
    const [vt, vr] = command();
    if (!velocityMode()) {
      return;
    }
    send(new MoveVelRequest({ velTrans: vt, velRot: vr }));
    if (held.size === 0 && joy === null) {
      if (timer !== null) {
        clearInterval(timer);
        timer = null;
      }
    } else if (timer === null) {
      timer = window.setInterval(drive, RESEND_MS);
    }
  };
  const typing = (e: KeyboardEvent) => {
    const el = e.target as HTMLElement | null;
    return el !== null && (el.tagName === "INPUT" || el.tagName === "SELECT" || el.tagName === "TEXTAREA");
  };
  document.addEventListener("keydown", (e) => {
    const k = KEYS[e.key];
    if (k === undefined || typing(e) || e.altKey || e.ctrlKey || !velocityMode()) {
      return;
    }
    e.preventDefault();
    if (!held.has(e.key)) {
      held.set(e.key, k);
      drive();
    }
  });
  const release = (key: string) => {
    if (held.delete(key)) {
      drive();
    }
  };
  document.addEventListener("keyup", (e) => release(e.key));
  window.addEventListener("blur", () => [...held.keys()].forEach(release));

  const pad = h("div", { class: "joystick", role: "application", tabindex: "0" });
  const knob = h("div", { class: "knob" });
  pad.append(knob);
  bind(pad, "motion.joystick", { text: false });
  const joyMove = (e: PointerEvent) => {
    const r = pad.getBoundingClientRect();
    const x = Math.max(-1, Math.min(1, ((e.clientX - r.left) / r.width) * 2 - 1));
    const y = Math.max(-1, Math.min(1, ((e.clientY - r.top) / r.height) * 2 - 1));
    joy = [-y, -x];
    knob.style.transform = `translate(${x * 40}px, ${y * 40}px)`;
  };
  pad.addEventListener("pointerdown", (e) => {
    pad.setPointerCapture(e.pointerId);
    joyMove(e);
    drive();
  });
  pad.addEventListener("pointermove", (e) => joy !== null && joyMove(e));
  const joyEnd = () => {
    joy = null;
    knob.style.transform = "";
    drive();
  };
  pad.addEventListener("pointerup", joyEnd);
  pad.addEventListener("pointercancel", joyEnd);
  const velocity = h(
    "div",
    { class: "mode-controls", "data-mode": "velocity" },
    h("p", { class: "hint" }),
    field("motion.transVel", vTrans),
    field("motion.rotVel", vRot),
    pad,
  );
  bind(velocity.querySelector(".hint") as HTMLElement, "motion.keysHint", { name: false });

  // ---- automatic
  const station = h("select");
  session.roadmap.subscribe((r) => {
    station.replaceChildren();
    try {
      for (const s of parseRoadmap(r.xml).stations) {
        station.append(h("option", { value: s.name }, s.name));
      }
    } catch {
      /* the map view says why */
    }
  });
  const ax = numberInput(0),
    ay = numberInput(0),
    aa = numberInput(0);
  const rx = numberInput(1000),
    ry = numberInput(0),
    ra = numberInput(0);
  const int = (i: HTMLInputElement, k = 1) => Math.round(Number(i.value) * k);
  const automatic = h(
    "div",
    { class: "mode-controls", "data-mode": "automatic" },
    h(
      "div",
      { class: "row" },
      field("motion.station", station),
      btn("motion.moveToStation", () => send(new MoveToStationRequest({ station: station.value }), "motion.sent")),
    ),
    h(
      "div",
      { class: "row" },
      field("motion.x", ax),
      field("motion.y", ay),
      field("motion.angle", aa),
      btn("motion.moveAbs", () =>
        send(new MoveAbsRequest({ x: int(ax), y: int(ay), angle: int(aa, 1000) }), "motion.sent"),
      ),
    ),
    h(
      "div",
      { class: "row" },
      field("motion.dx", rx),
      field("motion.dy", ry),
      field("motion.dangle", ra),
      btn("motion.moveRel", () =>
        send(new MoveRelRequest({ x: int(rx), y: int(ry), angle: int(ra, 1000) }), "motion.sent"),
      ),
    ),
    h(
      "div",
      { class: "row" },
      btn("motion.goFlag", () => {
        map.setTool("flag");
        map.sendFlag();
      }),
    ),
  );
  for (const [box, key] of [
    [ax, "motion.x"],
    [ay, "motion.y"],
    [aa, "motion.angle"],
  ] as const) {
    bind(box, key, { text: false });
  }

  // ---- post-process replay: guide 6.3 CMD_SET_EVENT
  const events: Array<[Event, Key]> = [
    [Event.EV_START_POST_PROCESS_RECORDING, "ev.1"],
    [Event.EV_STOP_POST_PROCESS_RECORDING, "ev.2"],
    [Event.EV_START_POST_PROCESS_REPLAY, "ev.3"],
    [Event.EV_STOP_POST_PROCESS_REPLAY, "ev.4"],
    [Event.EV_BREAK_POST_PROCESS_REPLAY, "ev.5"],
    [Event.EV_CONTINUE_POST_PROCESS_REPLAY, "ev.6"],
  ];
  const replay = h(
    "div",
    { class: "mode-controls", "data-mode": "replay" },
    ...events.map(([ev, key]) => btn(key, () => send(new SetEventRequest({ event: ev }), "motion.sent"))),
  );
  const note = h("p", { class: "mode-controls hint", "data-mode": "note" });
  root.append(commands(session, velocity, automatic, replay), note);

  const update = () => {
    const mode = status?.motionMode;
    const running = status?.operationState === OperationState.ST_OP_RUNNING;
    velocity.hidden = !velocityMode();
    automatic.hidden = mode !== MotionMode.MODE_MOTION_AUTOMATIC;
    replay.hidden = mode !== MotionMode.MODE_MOTION_POST_PROCESS_REPLAY;
    const noteKey: Record<number, Key> = { 0: "mode.note.0", 1: "mode.note.1", 5: "mode.note.5" };
    note.hidden = mode === undefined || noteKey[mode] === undefined;
    if (!note.hidden) {
      note.textContent = t(noteKey[mode!]);
    }
    for (const b of root.querySelectorAll("button")) {
      (b as HTMLButtonElement).disabled = !session.connected || !running;
    }
    root.dataset.running = String(running);
  };
  session.status.subscribe((s) => {
    const changed = s.motionMode !== status?.motionMode || s.operationState !== status?.operationState;
    status = s;
    if (changed) {
      update();
    }
  });
  session.conn.subscribe(() => {
    if (!session.connected) {
      status = null;
      held.clear();
      joy = null;
    }
    update();
  });
  onLanguage(update);
  return root;
}
