/**
 * The timeline of a recording (pltf gui --session FILE, issue 35): play, pause, speed, a scrubber over the
 * recording's times, and the requests the application sent that are not GETs (the commands, guide 6.3) as marks
 * on it, each with its name and time as a tooltip; a click on a mark goes there.
 *
 * Keyboard (anywhere but in a text field): Space plays or pauses, Left/Right step STEP_S back or forward
 * (Shift: BIG_STEP_S), Home/End go to the start or the end. The timeline takes these keys first: in a recording
 * the motion panel's arrow keys would send nothing anyway.
 *
 * Playing advances the time by the wall clock times the speed at each animation frame and asks the session for
 * the state there (seeks are coalesced by the session); it stops at the recording's end, with the last state shown.
 * The root says where it is for tests and benchmarks: data-time (Unix s shown), data-playing, data-start, data-end.
 */
import "./timeline.css";
import { field, h, setText } from "../dom";
import { bind, onLanguage, t } from "../i18n/i18n";
import type { RecordedEvent, RecordedSession, RecordingInfo } from "../session/recorded";

export const SPEEDS = [0.5, 1, 2, 4, 10, 20] as const;
export const STEP_S = 0.5;
export const BIG_STEP_S = 10;
/** More marks than this are thinned to one per pixel column's worth of time (an hour's commands). */
const MAX_MARKS = 600;

export interface Timeline {
  root: HTMLElement;
  seek(t: number): Promise<void>;
  play(): void;
  pause(): void;
  setSpeed(x: number): void;
}

/** The marks to draw: every event, or when there are more than `max`, the first of each 1/max of the length. */
export function thinMarks(events: RecordedEvent[], start: number, end: number, max = MAX_MARKS): RecordedEvent[] {
  if (events.length <= max) {
    return events;
  }
  const span = Math.max(end - start, 1e-9);
  const out: RecordedEvent[] = [];
  let lastBin = -1;
  for (const e of events) {
    const bin = Math.floor(((e.t - start) / span) * max);
    if (bin !== lastBin) {
      out.push(e);
      lastBin = bin;
    }
  }
  return out;
}

export function clock(seconds: number): string {
  const s = Math.max(0, seconds);
  const m = Math.floor(s / 60);
  return `${m}:${(s - 60 * m).toFixed(2).padStart(5, "0")}`;
}

export function timelinePanel(session: RecordedSession, info: RecordingInfo): Timeline {
  const { start, end } = info;
  let now = start;
  let speed = 1;
  let playing: number | null = null;

  const scrubber = h("input", {
    type: "range",
    class: "scrubber",
    min: 0,
    max: Math.max(end - start, 0),
    step: 0.01,
    value: 0,
  });
  bind(scrubber, "timeline.scrubber", { text: false });
  const position = h("output", { class: "position", "aria-live": "off" });
  const speedBox = h("select", {});
  for (const x of SPEEDS) {
    speedBox.append(h("option", { value: String(x), selected: x === 1 }, `${x}x`));
  }
  const marks = h("div", { class: "marks", role: "list" });
  bind(marks, "timeline.events", { text: false });
  const span = Math.max(end - start, 1e-9);
  const titleMarks = () => {
    for (const mark of marks.children as HTMLCollectionOf<HTMLElement>) {
      mark.title = t("timeline.mark", { name: mark.dataset.name ?? "", at: clock(Number(mark.dataset.t) - start) });
      mark.setAttribute("aria-label", mark.title);
    }
  };
  // the marks so far (an MCAP file's arrive while it is shown: data-marks "reading", then "all")
  const drawMarks = ({ events, complete }: { events: RecordedEvent[]; complete: boolean }) => {
    marks.replaceChildren(
      ...thinMarks(events, start, end).map((e) => {
        const mark = h("button", {
          type: "button",
          class: "mark",
          role: "listitem",
          style: `left: ${(100 * (e.t - start)) / span}%`,
          "data-name": e.name,
          "data-t": e.t,
        });
        mark.addEventListener("click", () => void go(e.t));
        return mark;
      }),
    );
    titleMarks();
    root.dataset.marks = complete ? "all" : "reading";
  };
  const playButton = h("button", { type: "button", class: "play" });
  playButton.addEventListener("click", () => toggle());
  const note = bind(h("p", { class: "timeline-note" }), "timeline.readOnly");
  const root = h(
    "section",
    { class: "timeline", "data-start": start, "data-end": end },
    h("div", { class: "timeline-controls" }, playButton, field("timeline.speed", speedBox), position),
    h("div", { class: "track" }, marks, scrubber),
    note,
  );
  bind(root, "timeline.caption", { text: false });

  const show = (at: number) => {
    now = at;
    root.dataset.time = String(at);
    if (document.activeElement !== scrubber || playing !== null) {
      scrubber.value = String(at - start);
    }
    setText(position, `${clock(at - start)} / ${clock(end - start)}`);
  };
  const showPlaying = () => {
    root.dataset.playing = String(playing !== null);
    const word = t(playing === null ? "timeline.play" : "timeline.pause");
    setText(playButton, word);
    playButton.setAttribute("aria-label", word);
  };
  const go = (at: number) => session.seek(Math.min(end, Math.max(start, at)));

  const pause = () => {
    if (playing !== null) {
      cancelAnimationFrame(playing);
      playing = null;
    }
    showPlaying();
  };
  const play = () => {
    if (playing !== null) {
      return;
    }
    let t0 = performance.now();
    let from = now >= end ? start : now;
    const frame = (wall: number) => {
      const at = Math.min(end, from + ((wall - t0) / 1000) * speed);
      const shown = go(at);
      if (at >= end) {
        playing = null;
        void shown.then(showPlaying); // "not playing" once the last state is shown
        return;
      }
      t0 = wall;
      from = at;
      playing = requestAnimationFrame(frame);
    };
    playing = requestAnimationFrame(frame);
    showPlaying();
  };
  const toggle = () => (playing === null ? play() : pause());
  const setSpeed = (x: number) => {
    speed = x;
    speedBox.value = String(x);
  };

  speedBox.addEventListener("change", () => setSpeed(Number(speedBox.value)));
  scrubber.addEventListener("input", () => void go(start + Number(scrubber.value)));
  session.time.subscribe(show);
  session.events.subscribe(drawMarks);
  onLanguage(titleMarks);
  onLanguage(showPlaying);

  const typing = (el: EventTarget | null) =>
    el instanceof HTMLElement && (el.tagName === "TEXTAREA" || el.tagName === "SELECT" || isTextInput(el));
  const KEYS: Record<string, (e: KeyboardEvent) => void> = {
    " ": () => toggle(),
    ArrowLeft: (e) => void go(now - (e.shiftKey ? BIG_STEP_S : STEP_S)),
    ArrowRight: (e) => void go(now + (e.shiftKey ? BIG_STEP_S : STEP_S)),
    Home: () => void go(start),
    End: () => void go(end),
  };
  window.addEventListener(
    "keydown",
    (e) => {
      const act = KEYS[e.key];
      if (act === undefined || e.altKey || e.ctrlKey || e.metaKey || typing(e.target)) {
        return;
      }
      e.preventDefault();
      e.stopImmediatePropagation();
      act(e);
    },
    { capture: true },
  );
  return { root, seek: go, play, pause, setSpeed };
}

function isTextInput(el: HTMLElement): boolean {
  return el instanceof HTMLInputElement && !["range", "checkbox", "radio", "button"].includes(el.type);
}

/** Load the session's recording and put its timeline after `before`; a recording that cannot be read is said. */
export async function mountTimeline(
  session: RecordedSession,
  before: HTMLElement,
  say: (text: string) => void,
): Promise<Timeline | null> {
  try {
    const timeline = timelinePanel(session, await session.load());
    before.after(timeline.root);
    return timeline;
  } catch (e) {
    say(t("timeline.failed", { detail: (e as Error).message }));
    return null;
  }
}
