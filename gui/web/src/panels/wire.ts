/**
 * The wire inspector (beyond the original): every telegram this tab sent or received, decoded by the generated
 * codec and shown for a person: each field by its spec name, texts as text (the codec's canonical dump writes
 * them in hex), repeated groups by their count and first item. GET_STATUS polling can be hidden; the view can be
 * paused. In a recording (session.seeked) a jump clears it and shows the telegrams before the time shown.
 */
import { h } from "../dom";
import { bind } from "../i18n/i18n";
import { dump, type Telegram } from "../pltf";
import type { PlatformSession, WireRecord } from "../session/session";

export const MAX_RECORDS = 500;
const MAX_STRING = 80;

function value(v: unknown): string {
  if (typeof v === "string") {
    return JSON.stringify(v.length > MAX_STRING ? `${v.slice(0, MAX_STRING)}...` : v);
  }
  if (v instanceof Uint8Array) {
    return Array.from(v.slice(0, 16), (b) => b.toString(16).padStart(2, "0")).join("") + (v.length > 16 ? "..." : "");
  }
  if (Array.isArray(v)) {
    const head = v
      .slice(0, typeof v[0] === "object" ? 1 : 8)
      .map(value)
      .join(",");
    return `[${v.length}${v.length > 0 ? `: ${head}${v.length > (typeof v[0] === "object" ? 1 : 8) ? ",..." : ""}` : ""}]`;
  }
  if (typeof v === "object" && v !== null) {
    return `{${Object.entries(v)
      .map(([k, x]) => `${k}=${value(x)}`)
      .join(" ")}}`;
  }
  return String(v);
}

/** A telegram's fields for a person (the opaque ones as the codec dumps them). */
export function readable(t: Telegram): string {
  if (t.telegramLayout.opaque) {
    return dump(t);
  }
  const props = t as unknown as Record<string, unknown>;
  return t.telegramLayout.fields.map((f) => `${f.name}=${value(props[f.prop])}`).join(" ");
}
const MAX_TEXT = 300;

/** What the inspector keeps of a telegram: its text, cut short (a decoded status holds ~20 KB of scan points). */
interface Line {
  text: string;
  name: string;
}

export function wirePanel(session: PlatformSession): { root: HTMLElement; onShow: (on: boolean) => void } {
  const records: Line[] = [];
  const pre = h("pre", { class: "wire", role: "log", tabindex: "0" });
  bind(pre, "menu.wire", { text: false });
  const hide = h("input", { type: "checkbox", checked: true });
  const pause = h("input", { type: "checkbox" });
  const hideCap = h("span");
  const pauseCap = h("span");
  bind(hideCap, "wire.hidePolling", { name: false });
  bind(hide, "wire.hidePolling", { text: false });
  bind(pauseCap, "wire.pause", { name: false });
  bind(pause, "wire.pause", { text: false });
  let shown = false;
  let dirty = false;
  const line = (r: WireRecord): Line => {
    let text = readable(r.telegram);
    if (text.length > MAX_TEXT) {
      text = `${text.slice(0, MAX_TEXT)}... (${r.bytes} bytes)`;
    }
    const name = r.telegram.telegramName;
    return {
      name,
      text: `${new Date(r.t).toISOString().slice(11, 23)} ${r.dir === "out" ? "->" : "<-"} ${name} ${text}`,
    };
  };
  let sinceSeek = 0; // the records published since the last seek: a recording publishes them before `seeked`
  session.wire.subscribe((r) => {
    records.push(line(r));
    sinceSeek++;
    if (records.length > 2 * MAX_RECORDS) {
      records.splice(0, records.length - MAX_RECORDS);
    }
    dirty = true;
  }, false);
  // a recording's jump: only its own frames, the telegrams before the time shown (a step adds to what is there)
  session.seeked.subscribe((s) => {
    if (s.plotsOnly) {
      return;
    }
    if (s.reset) {
      records.splice(0, Math.max(0, records.length - sinceSeek));
      dirty = true;
    }
    sinceSeek = 0;
  });
  const hidden = new Set(["CMD_GET_STATUS", "CMD_GET_POSITION", "CMD_GET_DEBUG_DATA", "CMD_GET_CAN_MESSAGES"]);
  const render = () => {
    if (!shown || !dirty || pause.checked) {
      return;
    }
    dirty = false;
    const shownRecords = records.filter((r) => !(hide.checked && hidden.has(r.name))).slice(-MAX_RECORDS);
    pre.textContent = shownRecords.map((r) => r.text).join("\n");
    pre.scrollTop = pre.scrollHeight;
  };
  hide.addEventListener("change", () => {
    dirty = true;
    render();
  });
  window.setInterval(render, 300);
  return {
    root: h(
      "div",
      {},
      h(
        "div",
        { class: "row" },
        h("label", { class: "check" }, hide, hideCap),
        h("label", { class: "check" }, pause, pauseCap),
      ),
      pre,
    ),
    onShow: (on) => {
      shown = on;
      dirty = true;
      render();
    },
  };
}
