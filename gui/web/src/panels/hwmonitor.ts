/**
 * The hardware monitor (guide 5.8): one tab per CAN node and the TCP views. Readings come from GET_STATUS;
 * the switches send CMD_SET_BRAKE, CMD_SET_DIGOUT and CMD_START_ULTRASONIC / CMD_STOP_ULTRASONIC. The CAN
 * Messages tab (the guide: "not implemented at the moment") lists the frames of CMD_GET_CAN_MESSAGES with filters
 * and sends frames (CMD_SEND_CAN_MESSAGE). TCP Client shows this tab's and the gateway's traffic, TCP Platform
 * the platform's own figures (CMD_GET_DEBUG_DATA).
 */
import { field, h, setText } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import {
  AddCanListeningIdRequest,
  BoardType,
  BrakeState,
  CanBufferMode,
  type CanMessage,
  GetCanMessagesRequest,
  type GetStatusReply,
  MotorIndex,
  OutputLevel,
  RemoveCanListeningIdRequest,
  SendCanMessageRequest,
  SetBrakeRequest,
  SetDigoutRequest,
  StartUltrasonicRequest,
  StopUltrasonicRequest,
  type Telegram,
} from "../pltf";
import type { PlatformSession } from "../session/session";
import { commands } from "./control";

/** erratum E-HW-005: the board status word; -1 = the node is not connected. */
const STATUS_BITS: Array<[number, string]> = [
  [0x01, "not initialized"],
  [0x02, "self test failed"],
  [0x04, "emergency stop"],
  [0x08, "over-temperature"],
  [0x100, "node timeout"],
  [0x200, "frames lost"],
  [0x400, "CAN bus-off"],
];
const BOARD_BITS: Record<string, Array<[number, string]>> = {
  motor: [
    [0x10, "brake engaged"],
    [0x20, "setpoint timeout"],
    [0x40, "stall"],
  ],
  io: [[0x10, "low battery"]],
  us: [[0x10, "measuring"]],
};
const US_MEASURING = 0x10;

export function statusWords(word: number, board = ""): string {
  if (word === -1) {
    return "not connected";
  }
  const names = [...STATUS_BITS, ...(BOARD_BITS[board] ?? [])].filter(([bit]) => word & bit).map(([, n]) => n);
  return names.length === 0 ? `ok (${word})` : `${names.join(", ")} (0x${word.toString(16)})`;
}

type Row = [Key | string, (s: GetStatusReply) => string];

/** Show each status; in a recording (session.seeked) `clear` when the time shown has no status yet, as live
 * before the first reply. */
function onStatus(session: PlatformSession, show: (s: GetStatusReply) => void, clear: () => void): void {
  session.status.subscribe(show);
  session.seeked.subscribe(() => session.status.last === undefined && clear());
}

function table(rows: Row[], session: PlatformSession): HTMLElement {
  const body = h("tbody");
  const cells = rows.map(([label]) => {
    const th = h("th", { scope: "row" });
    const td = h("td");
    if (label.includes(".")) {
      bind(th, label as Key, { name: false });
    } else {
      th.textContent = label;
    }
    body.append(h("tr", {}, th, td));
    return td;
  });
  onStatus(
    session,
    (s) => rows.forEach(([, get], i) => setText(cells[i], get(s))),
    () => cells.forEach((c) => setText(c, "")),
  );
  return h("table", {}, body);
}

function send(session: PlatformSession, tg: Telegram, say: (s: string) => void): void {
  try {
    session.send(tg);
  } catch (e) {
    say((e as Error).message);
  }
}

function checkboxes(
  n: number,
  label: (i: number) => string,
  onToggle: (i: number, on: boolean) => void,
): { root: HTMLElement; boxes: HTMLInputElement[] } {
  const boxes: HTMLInputElement[] = [];
  const root = h("div", { class: "bits" });
  for (let i = 0; i < n; i++) {
    const box = h("input", { type: "checkbox", "aria-label": label(i) });
    box.addEventListener("change", () => onToggle(i, box.checked));
    boxes.push(box);
    root.append(h("label", { class: "bit" }, box, String(i + 1)));
  }
  return { root, boxes };
}

function leds(
  n: number,
  label: (i: number) => string,
  get: (s: GetStatusReply) => number,
  session: PlatformSession,
): HTMLElement {
  const { root, boxes } = checkboxes(n, label, () => undefined);
  boxes.forEach((b) => (b.disabled = true));
  onStatus(
    session,
    (s) => boxes.forEach((b, i) => (b.checked = ((get(s) >> i) & 1) === 1)),
    () => boxes.forEach((b) => (b.checked = false)),
  );
  return root;
}

function heading(key: Key): HTMLElement {
  const el = h("h3");
  bind(el, key, { name: false });
  return el;
}

function motorTab(session: PlatformSession, say: (s: string) => void): HTMLElement {
  const brake = (motor: MotorIndex, state: BrakeState, key: Key) => {
    const b = h("button", { type: "button" });
    bind(b, key);
    b.addEventListener("click", () => send(session, new SetBrakeRequest({ motor, state }), say));
    return b;
  };
  return h(
    "div",
    {},
    table(
      [
        ["hw.motorRight", (s) => statusWords(s.motorRightStatus, "motor")],
        ["hw.motorLeft", (s) => statusWords(s.motorLeftStatus, "motor")],
        ["hw.tempRight", (s) => `${s.motorRightTemp} °C`],
        ["hw.tempLeft", (s) => `${s.motorLeftTemp} °C`],
        ["hw.velocity", (s) => `${s.velTrans} mm/s, ${s.velRot} mrad/s`],
      ],
      session,
    ),
    commands(
      session,
      h(
        "div",
        { class: "row" },
        brake(MotorIndex.CANNODE_MOTORRIGHT, BrakeState.BRAKE_ENABLED, "hw.brakeRightOn"),
        brake(MotorIndex.CANNODE_MOTORRIGHT, BrakeState.BRAKE_DISABLED, "hw.brakeRightOff"),
        brake(MotorIndex.CANNODE_MOTORLEFT, BrakeState.BRAKE_ENABLED, "hw.brakeLeftOn"),
        brake(MotorIndex.CANNODE_MOTORLEFT, BrakeState.BRAKE_DISABLED, "hw.brakeLeftOff"),
      ),
    ),
  );
}

function ioTab(session: PlatformSession, say: (s: string) => void): HTMLElement {
  const outs = checkboxes(
    16,
    (i) => `${t("hw.digitalOut")} ${i + 1}`,
    (i, on) =>
      send(
        session,
        new SetDigoutRequest({
          board: BoardType.TYPE_IOBOARD,
          channel: i,
          value: on ? OutputLevel.OUTPUT_HIGH : OutputLevel.OUTPUT_LOW,
        }),
        say,
      ),
  );
  onStatus(
    session,
    (s) =>
      outs.boxes.forEach((b, i) => {
        if (document.activeElement !== b) {
          b.checked = ((s.ioDigitalOut >> i) & 1) === 1;
        }
      }),
    () => outs.boxes.forEach((b) => (b.checked = false)),
  );
  return h(
    "div",
    {},
    table(
      [
        ["hw.status", (s) => statusWords(s.ioStatus, "io")],
        ["status.battery", (s) => `${(s.ioBatteryVoltage / 1000).toFixed(2)} V`],
        ["hw.analogIn", (s) => s.ioAnalogIn.join(", ")],
      ],
      session,
    ),
    heading("hw.digitalIn"),
    leds(
      16,
      (i) => `${t("hw.digitalIn")} ${i + 1}`,
      (s) => s.ioDigitalIn,
      session,
    ),
    heading("hw.digitalOut"),
    commands(session, outs.root),
  );
}

function relayTab(session: PlatformSession, say: (s: string) => void): HTMLElement {
  // erratum E-HW-010: 8 relays, no readback in the status telegram: the boxes show what this GUI set
  const outs = checkboxes(
    8,
    (i) => `${t("hw.relayOut")} ${i + 1}`,
    (i, on) =>
      send(
        session,
        new SetDigoutRequest({
          board: BoardType.TYPE_RELAYBOARD,
          channel: i,
          value: on ? OutputLevel.OUTPUT_HIGH : OutputLevel.OUTPUT_LOW,
        }),
        say,
      ),
  );
  return h(
    "div",
    {},
    table(
      [
        ["hw.status", (s) => statusWords(s.relayStatus)],
        ["hw.analogIn", (s) => s.relayAnalogIn.join(", ")],
        ["hw.opto", (s) => s.relayOptoDistance.map((d) => `${d} mm`).join(", ")],
      ],
      session,
    ),
    heading("hw.relayOut"),
    commands(session, outs.root),
    heading("hw.digitalIn"),
    leds(
      8,
      (i) => `${t("hw.digitalIn")} ${i + 1}`,
      (s) => s.relayDigitalIn & 0xff,
      session,
    ),
    // erratum E-HW-011: the keypad keys are bits 8-15 of relay_digital_in
    heading("hw.keypad"),
    leds(
      8,
      (i) => `${t("hw.key")} ${i + 1}`,
      (s) => (s.relayDigitalIn >> 8) & 0xff,
      session,
    ),
  );
}

function usTab(session: PlatformSession, say: (s: string) => void): HTMLElement {
  // guide 5.8 USBoard: "16 sensors ... can be enabled and disabled individually through the command 'start US'";
  // erratum E-CMD-005: the active channels are a bit mask (bit n = sensor n+1)
  let mask: number | null = null;
  const start = () => send(session, new StartUltrasonicRequest({ activeChannels: mask ?? 0xffff }), say);
  const sensors = checkboxes(
    16,
    (i) => `${t("hw.sensor")} ${i + 1}`,
    (i, on) => {
      mask = ((mask ?? 0xffff) & ~(1 << i)) | (on ? 1 << i : 0);
      start();
    },
  );
  const distances = sensors.boxes.map(() => h("span", { class: "distance" }));
  sensors.boxes.forEach((b, i) => b.parentElement!.append(distances[i]));
  onStatus(
    session,
    (s) => {
      const measuring = s.usStatus !== -1 && (s.usStatus & US_MEASURING) !== 0;
      if (mask === null && measuring) {
        mask = s.usDistance.reduce((m, d, i) => (d > 0 ? m | (1 << i) : m), 0);
      }
      sensors.boxes.forEach((b, i) => {
        b.checked = mask === null ? false : ((mask >> i) & 1) === 1;
        setText(distances[i], measuring ? `${s.usDistance[i]} mm` : "-");
      });
    },
    () => {
      mask = null;
      sensors.boxes.forEach((b, i) => {
        b.checked = false;
        setText(distances[i], "");
      });
    },
  );
  const startBtn = h("button", { type: "button" });
  bind(startBtn, "hw.startUs");
  startBtn.addEventListener("click", start);
  const stopBtn = h("button", { type: "button" });
  bind(stopBtn, "hw.stopUs");
  stopBtn.addEventListener("click", () => send(session, new StopUltrasonicRequest(), say));
  return h(
    "div",
    {},
    table(
      [
        ["hw.status", (s) => statusWords(s.usStatus, "us")],
        ["hw.analogIn", (s) => s.usAnalogIn.join(", ")],
      ],
      session,
    ),
    commands(session, h("div", { class: "row" }, startBtn, stopBtn)),
    heading("hw.sensors"),
    commands(session, sensors.root),
  );
}

function radarTab(session: PlatformSession): HTMLElement {
  return table(
    [
      ["hw.status", (s) => statusWords(s.radarStatus)],
      ...[0, 1, 2, 3].map((i): Row => [`Radar ${i + 1}`, (s) => `${s.radarVelocity[i]} mm/s`]),
    ],
    session,
  );
}

function hex(bytes: number[]): string {
  return bytes.map((b) => b.toString(16).padStart(2, "0")).join(" ");
}

function canTab(session: PlatformSession, say: (s: string) => void): { root: HTMLElement; frames: CanMessage[] } {
  const frames: CanMessage[] = [];
  const listenId = h("input", { type: "text", value: "0x700", size: "8" });
  const filter = h("input", { type: "text", placeholder: "0x7.. / 0x123", size: "10" });
  const sendId = h("input", { type: "text", value: "0x700", size: "8" });
  const sendData = h("input", { type: "text", value: "00 00 00 00 00 00 00 00", size: "26" });
  const body = h("tbody");
  const parseId = (text: string): number | null => {
    const v = Number(text.trim());
    return Number.isInteger(v) && v >= 0 && v <= 0x7ff ? v : null;
  };
  const idBtn = (key: Key, make: (id: number) => Telegram) => {
    const b = h("button", { type: "button" });
    bind(b, key);
    b.addEventListener("click", () => {
      const id = parseId(listenId.value);
      if (id === null) {
        say(t("hw.badCanId"));
        return;
      }
      send(session, make(id), say);
    });
    return b;
  };
  const sendBtn = h("button", { type: "button" });
  bind(sendBtn, "hw.sendFrame");
  sendBtn.addEventListener("click", () => {
    const id = parseId(sendId.value);
    const data = sendData.value
      .trim()
      .split(/[\s,]+/)
      .filter(Boolean)
      .map((b) => Number.parseInt(b, 16));
    if (id === null) {
      say(t("hw.badCanId"));
    } else if (data.length > 8 || data.some((b) => !(b >= 0 && b <= 255))) {
      say(t("hw.badCanData"));
    } else {
      while (data.length < 8) {
        data.push(0);
      }
      send(session, new SendCanMessageRequest({ canId: id, data }), say);
    }
  });
  const render = () => {
    const f = filter.value.trim().toLowerCase().replace(/^0x/, "");
    // the id as shown, three hex digits: "0x02." matches 0x020 .. 0x02f
    const pattern = new RegExp(`^${f.replace(/[^0-9a-f.]/g, "").replace(/\./g, "[0-9a-f]")}$`);
    const shown = frames.filter((m) => f === "" || pattern.test(m.canId.toString(16).padStart(f.length, "0")));
    body.replaceChildren(
      ...shown
        .slice(-200)
        .reverse()
        .map((m) =>
          h(
            "tr",
            {},
            h("td", {}, m.timestamp.toFixed(3)),
            h("td", {}, `0x${m.canId.toString(16).padStart(3, "0")}`),
            h("td", {}, hex(m.data)),
          ),
        ),
    );
  };
  filter.addEventListener("input", render);
  session.can.subscribe((r) => {
    frames.push(...r.messages);
    frames.splice(0, Math.max(0, frames.length - 2000));
    render();
  });
  // a recording's jump: the frames of the last reply at the time shown, none before the first
  session.seeked.subscribe((s) => {
    if (s.reset && !s.plotsOnly) {
      frames.splice(0, frames.length, ...(session.can.last?.messages ?? []));
      render();
    }
  });
  const head = h("tr", {}, h("th", {}, "t (s)"), h("th", {}, "id"), h("th", {}, "data"));
  const root = h(
    "div",
    {},
    commands(
      session,
      h(
        "div",
        { class: "row" },
        field("hw.canId", listenId),
        idBtn("hw.listen", (id) => new AddCanListeningIdRequest({ canId: id })),
        idBtn("hw.unlisten", (id) => new RemoveCanListeningIdRequest({ canId: id })),
      ),
    ),
    h("div", { class: "row" }, field("hw.filter", filter)),
    h("table", { "aria-label": "CAN" }, h("thead", {}, head), body),
    commands(session, h("div", { class: "row" }, field("hw.canId", sendId), field("hw.canData", sendData), sendBtn)),
  );
  return { root, frames };
}

function tcpClientTab(session: PlatformSession): HTMLElement {
  const mine = h("tbody");
  const gw = h("tbody");
  let last = { ...session.traffic, at: performance.now() };
  const row = (k: string, v: string) => h("tr", {}, h("th", { scope: "row" }, k), h("td", {}, v));
  const tick = () => {
    const tr = session.traffic;
    const now = performance.now();
    const dt = Math.max((now - last.at) / 1000, 1e-3);
    const rtt = [...tr.rtt].sort((a, b) => a - b);
    mine.replaceChildren(
      row(
        t("hw.sentPerS"),
        `${((tr.telegramsOut - last.telegramsOut) / dt).toFixed(1)} telegrams, ${((tr.bytesOut - last.bytesOut) / dt).toFixed(0)} B`,
      ),
      row(
        t("hw.receivedPerS"),
        `${((tr.telegramsIn - last.telegramsIn) / dt).toFixed(1)} telegrams, ${((tr.bytesIn - last.bytesIn) / dt).toFixed(0)} B`,
      ),
      row(
        t("hw.rtt"),
        rtt.length
          ? `${rtt[Math.floor(rtt.length / 2)].toFixed(1)} ms median, ${rtt[rtt.length - 1].toFixed(1)} ms max`
          : "-",
      ),
      row(t("hw.errors"), String(tr.errors)),
      row(t("hw.reconnects"), String(tr.reconnects)),
    );
    last = { ...tr, at: now };
    session.askStats();
  };
  session.gatewayStats.subscribe((s) => {
    gw.replaceChildren(
      ...Object.entries(s)
        .filter(([k]) => k !== "event" && k !== "target")
        .map(([k, v]) => row(k, v === null ? "-" : String(typeof v === "number" ? Math.round(v * 10) / 10 : v))),
    );
  });
  window.setInterval(tick, 1000);
  const h1 = heading("hw.thisTab");
  const h2 = heading("hw.gateway");
  return h("div", {}, h1, h("table", {}, mine), h2, h("table", {}, gw));
}

function tcpPlatformTab(session: PlatformSession): HTMLElement {
  const body = h("tbody");
  session.seeked.subscribe(() => session.debug.last === undefined && body.replaceChildren());
  session.debug.subscribe((d) => {
    const rows: Array<[string, string]> = [
      ["received telegrams/s", String(d.tcpReceivedTelegramsPerS)],
      ["sent telegrams/s", String(d.tcpSentTelegramsPerS)],
      ["received bytes/s", String(d.tcpReceivedBytesPerS)],
      ["sent bytes/s", String(d.tcpSentBytesPerS)],
      ["average receive time (s)", String(d.tcpAvgReceiveTime)],
      ["average send time (s)", String(d.tcpAvgSendTime)],
      ["average wait time (s)", String(d.tcpAvgWaitTime)],
      ["wait time (%)", String(d.tcpWaitTimePercent)],
    ];
    body.replaceChildren(...rows.map(([k, v]) => h("tr", {}, h("th", { scope: "row" }, k), h("td", {}, v))));
  });
  return h("div", {}, h("table", {}, body));
}

export function hardwareMonitor(
  session: PlatformSession,
  say: (s: string) => void,
): { root: HTMLElement; onShow: (on: boolean) => void } {
  const can = canTab(session, say);
  const tabs: Array<[string, Key, HTMLElement, string?]> = [
    ["motor", "hw.motor", motorTab(session, say)],
    ["io", "hw.ioboard", ioTab(session, say)],
    ["relay", "hw.relayboard", relayTab(session, say)],
    ["us", "hw.usboard", usTab(session, say)],
    ["radar", "hw.radar", radarTab(session)],
    ["can", "hw.can", can.root, "can"],
    ["tcpc", "hw.tcpClient", tcpClientTab(session)],
    ["tcpp", "hw.tcpPlatform", tcpPlatformTab(session)],
  ];
  session.poll("can", () => new GetCanMessagesRequest({ delete: CanBufferMode.CAN_MESSAGES_DELETE }), 5);
  const list = h("div", { role: "tablist", class: "dock-tabs" });
  bind(list, "menu.hardwareMonitor", { text: false });
  const root = h("div", { class: "hw" }, list);
  let shown = false;
  let current = "motor";
  const select = (id: string) => {
    current = id;
    for (const [tid, , pane, poll] of tabs) {
      const on = tid === id;
      const tab = list.querySelector<HTMLElement>(`#hw-tab-${tid}`)!;
      tab.setAttribute("aria-selected", String(on));
      pane.hidden = !on;
      if (poll) {
        session.setPolling(poll, on && shown);
      }
    }
  };
  for (const [id, key, pane] of tabs) {
    const tab = h("button", { type: "button", role: "tab", id: `hw-tab-${id}`, "aria-selected": "false" });
    bind(tab, key);
    tab.addEventListener("click", () => select(id));
    list.append(tab);
    pane.setAttribute("role", "tabpanel");
    bind(pane, key, { text: false });
    root.append(pane);
  }
  select("motor");
  return {
    root,
    onShow: (on) => {
      shown = on;
      select(current);
    },
  };
}
