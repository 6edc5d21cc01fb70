/** The log panel (beyond the original): the platform's protocol queue from CMD_GET_DEBUG_DATA, polled at 1 Hz. */
import { h } from "../dom";
import { bind } from "../i18n/i18n";
import type { PlatformSession } from "../session/session";

export const MAX_LINES = 1000;

export function logPanel(session: PlatformSession): HTMLElement {
  const pre = h("pre", { class: "log", role: "log", tabindex: "0" });
  bind(pre, "menu.log", { text: false });
  let previous: string[] = [];
  const lines: string[] = [];
  // a recording's jump (session.seeked): the queue of the last GET_DEBUG_DATA reply at the time shown, or nothing
  session.seeked.subscribe((s) => {
    if (s.reset && !s.plotsOnly) {
      previous = session.debug.last?.protocolQueue.map((e) => e.entry) ?? [];
      lines.splice(0, lines.length, ...previous);
      pre.textContent = lines.join("\n");
    }
  });
  session.debug.subscribe((d) => {
    const queue = d.protocolQueue.map((e) => e.entry);
    // the queue is a sliding window of the last entries: append what follows the overlap with the last one
    let start = 0;
    for (let k = Math.min(previous.length, queue.length); k > 0; k--) {
      if (previous.slice(previous.length - k).every((line, i) => line === queue[i])) {
        start = k;
        break;
      }
    }
    previous = queue;
    const fresh = queue.slice(start);
    if (fresh.length === 0) {
      return;
    }
    lines.push(...fresh);
    lines.splice(0, Math.max(0, lines.length - MAX_LINES));
    const atEnd = pre.scrollTop + pre.clientHeight >= pre.scrollHeight - 4;
    pre.textContent = lines.join("\n");
    if (atEnd) {
      pre.scrollTop = pre.scrollHeight;
    }
  });
  return pre;
}
