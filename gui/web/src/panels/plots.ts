/**
 * Plots over a time window (beyond the original): commanded and measured velocity (GET_STATUS vel_trans,
 * GET_POSITION vel_trans), battery voltage, localization quality (the deviation ellipse's axes, mm). Each plot is
 * a small canvas with an accessible name and its latest value as text.
 */
import { h } from "../dom";
import { bind, type Key, onLanguage, t } from "../i18n/i18n";
import { GetPositionReply, GetPositionRequest, GetStatusReply, type Telegram } from "../pltf";
import type { PlatformSession } from "../session/session";

export const WINDOW_S = 60;

interface Series {
  label: string;
  color: string;
  points: Array<[number, number]>;
}

class Plot {
  readonly root: HTMLElement;
  readonly canvas = h("canvas", { class: "plot", role: "img" });
  readonly latest = h("output");
  constructor(
    readonly key: Key,
    readonly unit: string,
    readonly series: Series[],
  ) {
    const title = h("h3");
    bind(title, key, { name: false });
    bind(this.canvas, key, { text: false });
    bind(this.latest, key, { text: false });
    this.root = h("div", { class: "plot-box" }, title, this.canvas, this.latest);
  }

  add(i: number, now: number, v: number): void {
    const pts = this.series[i].points;
    pts.push([now, v]);
    while (pts.length > 0 && pts[0][0] < now - WINDOW_S * 1000) {
      pts.shift();
    }
  }

  clear(): void {
    this.series.forEach((s) => (s.points.length = 0));
  }

  draw(now: number): void {
    const c = this.canvas;
    c.dataset.points = String(this.series[0].points.length);
    const w = (c.width = c.clientWidth || 300);
    const hgt = (c.height = c.clientHeight || 120);
    const ctx = c.getContext("2d")!;
    ctx.clearRect(0, 0, w, hgt);
    const all = this.series.flatMap((s) => s.points.map((p) => p[1]));
    if (all.length === 0) {
      return;
    }
    let lo = Math.min(...all),
      hi = Math.max(...all);
    if (hi - lo < 1e-9) {
      lo -= 1;
      hi += 1;
    }
    ctx.font = "10px sans-serif";
    ctx.fillStyle = "#607d8b";
    ctx.fillText(`${hi.toFixed(1)} ${this.unit}`, 2, 10);
    ctx.fillText(`${lo.toFixed(1)}`, 2, hgt - 2);
    for (const s of this.series) {
      ctx.strokeStyle = s.color;
      ctx.beginPath();
      s.points.forEach(([tm, v], k) => {
        const x = w - ((now - tm) / (WINDOW_S * 1000)) * w;
        const y = hgt - 4 - ((v - lo) / (hi - lo)) * (hgt - 16);
        if (k === 0) {
          ctx.moveTo(x, y);
        } else {
          ctx.lineTo(x, y);
        }
      });
      ctx.stroke();
    }
    this.latest.textContent = this.series
      .map((s) => `${s.label} ${s.points.at(-1)?.[1].toFixed(1) ?? "-"} ${this.unit}`)
      .join(", ");
  }
}

export function plotsPanel(session: PlatformSession): { root: HTMLElement; onShow: (on: boolean) => void } {
  const vel = new Plot("plot.velocity", "mm/s", [
    { label: "commanded", color: "#1565c0", points: [] },
    { label: "measured", color: "#e65100", points: [] },
  ]);
  const battery = new Plot("status.battery", "V", [{ label: "", color: "#2e7d32", points: [] }]);
  const loc = new Plot("plot.localization", "mm", [
    { label: "major", color: "#6a1b9a", points: [] },
    { label: "minor", color: "#00838f", points: [] },
  ]);
  const plots = [vel, battery, loc];
  let shown = false;
  // a recording (session.seeked) plots its own times, up to the time shown, and only the history it is given
  let recorded = false;
  let clock = () => performance.now();
  const take = (now: number, r: Telegram) => {
    if (r instanceof GetStatusReply) {
      vel.add(0, now, r.velTrans);
      battery.add(0, now, r.ioBatteryVoltage / 1000);
      loc.add(0, now, r.covMajor);
      loc.add(1, now, r.covMinor);
    } else if (r instanceof GetPositionReply) {
      vel.add(1, now, r.velTrans);
    }
  };
  session.status.subscribe((s) => recorded || take(clock(), s));
  session.replies.subscribe((r) => recorded || (r instanceof GetPositionReply && take(clock(), r)));
  session.seeked.subscribe((s) => {
    recorded = true;
    clock = () => s.t * 1000;
    if (s.reset) {
      plots.forEach((p) => p.clear());
    }
    s.history.forEach((h) => take(h.t * 1000, h.telegram));
  });
  session.poll("position", () => new GetPositionRequest(), 5);
  window.setInterval(() => shown && plots.forEach((p) => p.draw(clock())), 250);
  const note = h("p", { class: "hint" });
  onLanguage(() => (note.textContent = t("plot.window", { s: WINDOW_S })));
  return {
    root: h("div", {}, note, ...plots.map((p) => p.root)),
    onShow: (on) => {
      shown = on;
      session.setPolling("position", on);
    },
  };
}
