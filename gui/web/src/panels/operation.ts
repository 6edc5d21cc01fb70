/**
 * Operation (guide 4.2 figure 2, 5.6): the state chart's commands as buttons, each enabled only in the states
 * where the chart draws it, and the motion mode combo box with all seven modes (guide 4.3).
 *
 * The table below is what the GUI reads off the status telegram; the platform decides (a refused command
 * changes nothing). GET_STATUS reports one ST_OP_NOT_INITIALIZED for "CAN down" and "CAN connected"
 * (erratum E-SRV-001), so Init sends CMD_CONNECT_TO_PLTF then CMD_INIT_PLTF: guide 4.2 "The initialization
 * process starts with the command CMD_CONNECT_CAN ... The command CMD_INIT_CAN initializes all hardware"
 * (erratum E-CMD-002: these are CMD_CONNECT_TO_PLTF and CMD_INIT_PLTF).
 */
import { h } from "../dom";
import { bind, type Key, onLanguage, t } from "../i18n/i18n";
import {
  BreakRequest,
  ConnectToPltfRequest,
  ContinueRequest,
  EmergencyState,
  type GetStatusReply,
  InitPltfRequest,
  MotionMode,
  OperationState,
  SetModeRequest,
  ShutdownPltfRequest,
  StartRequest,
  StopRequest,
  type Telegram,
} from "../pltf";
import type { PlatformSession } from "../session/session";
import { commands } from "./control";

const {
  ST_OP_READY: READY,
  ST_OP_RUNNING: RUNNING,
  ST_OP_BREAKED: BREAKED,
  ST_OP_NOT_INITIALIZED: NOT_INIT,
} = OperationState;

interface Command {
  key: Key;
  shortcut: string;
  send: () => Telegram[];
  /** guide 4.2 figure 2: the states the command is drawn from */
  from: OperationState[];
  blockedByEmergency: boolean;
}

export const COMMANDS: Command[] = [
  {
    key: "op.init",
    shortcut: "Alt+I",
    send: () => [new ConnectToPltfRequest(), new InitPltfRequest()],
    from: [NOT_INIT],
    blockedByEmergency: false,
  },
  // guide 6.3 CMD_START / 4.2: "In the state 'Initialized' the platform can be started"
  { key: "op.start", shortcut: "Alt+S", send: () => [new StartRequest()], from: [READY], blockedByEmergency: true },
  { key: "op.break", shortcut: "Alt+B", send: () => [new BreakRequest()], from: [RUNNING], blockedByEmergency: false },
  {
    key: "op.continue",
    shortcut: "Alt+C",
    send: () => [new ContinueRequest()],
    from: [BREAKED],
    blockedByEmergency: true,
  },
  // guide 6.3 CMD_STOP: "The operation state changes into the state 'Ready'"
  {
    key: "op.stop",
    shortcut: "Alt+X",
    send: () => [new StopRequest()],
    from: [RUNNING, BREAKED],
    blockedByEmergency: false,
  },
  // guide 6.3 CMD_SHUTDOWN_PLTF: "Used to shutdown the CAN communication"
  {
    key: "op.shutdownCan",
    shortcut: "",
    send: () => [new ShutdownPltfRequest()],
    from: [NOT_INIT, READY, RUNNING, BREAKED],
    blockedByEmergency: false,
  },
];

/** The commands' tooltips (issue 35): what each sends and from which state (guide 4.2, 6.3). */
const OP_TIPS: Partial<Record<Key, Key>> = {
  "op.init": "op.tipInit",
  "op.start": "op.tipStart",
  "op.break": "op.tipBreak",
  "op.continue": "op.tipContinue",
  "op.stop": "op.tipStop",
  "op.shutdownCan": "op.tipShutdownCan",
};

export function allowed(c: Command, s: GetStatusReply | null): boolean {
  if (s === null) {
    return false;
  }
  return (
    c.from.includes(s.operationState) && !(c.blockedByEmergency && s.emergencyState === EmergencyState.ST_EM_ACTIVE)
  );
}

export const MODES: Array<[MotionMode, Key]> = [
  [MotionMode.MODE_MOTION_NO, "mode.0"],
  [MotionMode.MODE_MOTION_JOYHARD, "mode.1"],
  [MotionMode.MODE_MOTION_JOYSOFT, "mode.2"],
  [MotionMode.MODE_MOTION_VEL, "mode.3"],
  [MotionMode.MODE_MOTION_AUTOMATIC, "mode.4"],
  [MotionMode.MODE_MOTION_PROGRAM, "mode.5"],
  [MotionMode.MODE_MOTION_POST_PROCESS_REPLAY, "mode.6"],
];

export function operationPanel(session: PlatformSession, say: (text: string) => void): HTMLElement {
  const bar = h("div", { role: "toolbar", class: "operation" });
  bind(bar, "op.toolbar", { text: false });
  let status: GetStatusReply | null = null;
  const sendAll = (telegrams: Telegram[]): boolean => {
    try {
      telegrams.forEach((tg) => session.send(tg));
      return true;
    } catch (e) {
      say((e as Error).message);
      return false;
    }
  };
  const buttons = COMMANDS.map((c) => {
    const b = h("button", { type: "button", "aria-keyshortcuts": c.shortcut || false });
    bind(b, c.key, { title: OP_TIPS[c.key] });
    // issue 35: a message for every action: what was sent, by the telegrams' names (guide 6.3)
    b.addEventListener("click", () => {
      const telegrams = c.send();
      if (sendAll(telegrams)) {
        say(t("op.sent", { what: t(c.key), telegrams: telegrams.map((tg) => tg.telegramName).join(", ") }));
      }
    });
    return b;
  });
  // guide 5.6: "For starting a motion mode the platform has to be in the state 'Ready'. Select in to motion mode combo box"
  const select = h("select", { class: "motion-mode" });
  for (const [mode, key] of MODES) {
    const opt = h("option", { value: String(mode) });
    bind(opt, key, { name: false });
    select.append(opt);
  }
  const caption = h("span");
  bind(caption, "status.motionMode", { name: false });
  bind(select, "status.motionMode", { text: false });
  // issue 33: the state chart's buttons and the mode only while this tab may command (panels/control.ts)
  bar.append(commands(session, ...buttons, h("label", { class: "field" }, caption, select)));
  let userPicked = false;
  select.addEventListener("focus", () => (userPicked = true));
  select.addEventListener("blur", () => (userPicked = false));
  select.addEventListener("change", () => {
    sendAll([new SetModeRequest({ mode: Number(select.value) as MotionMode })]);
    say(t("op.modeSent", { mode: select.selectedOptions[0]?.textContent ?? select.value }));
  });
  const update = () => {
    COMMANDS.forEach((c, i) => (buttons[i].disabled = !session.connected || !allowed(c, status)));
    select.disabled = !session.connected || status?.operationState !== READY;
    if (status !== null && !userPicked) {
      select.value = String(status.motionMode);
    }
  };
  session.status.subscribe((s) => {
    status = s;
    update();
  });
  session.conn.subscribe(() => {
    if (!session.connected) {
      status = null;
    }
    update();
  });
  onLanguage(update);
  document.addEventListener("keydown", (e) => {
    if (!e.altKey) {
      return;
    }
    const i = COMMANDS.findIndex((c) => c.shortcut === `Alt+${e.key.toUpperCase()}`);
    if (i >= 0 && !buttons[i].disabled && session.mayCommand) {
      e.preventDefault();
      buttons[i].click();
    }
  });
  return bar;
}
