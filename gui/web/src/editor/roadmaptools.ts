/**
 * The roadmap editor's state and its tools (guide 5.5), one named function per tool and action, apart from the
 * panel (roadmappanel.ts builds the DOM and hands these the pointer): "Select" (drag a station), "Add station"
 * (click; name and angle from the fields), "Add edge" (click two stations), "Path points" (select an edge, click
 * to add a point, drag one, right-click deletes it), typed coordinates and Delete. No DOM and no catalog here:
 * what a tool says goes through `RoadmapToolEnv.text`, so test/roadmaptools.test.ts runs them on a real history.
 */
import type { Key } from "../i18n/i18n";
import type { Roadmap } from "../scene/roadmap";
import { type Camera, toScreen } from "../view/camera";
import {
  addEdge,
  addStation,
  deleteStation,
  type Edit,
  moveStation,
  type RoadmapDoc,
  type RoadmapHistory,
} from "./roadmapdoc";
import { type Action, act, actionMessage } from "./history";
import { deletePathPoint, edgeAt, edgePath, insertPathPoint, movePathPoint, pathPointAt } from "./roadmappath";

export type RmTool = "select" | "addStation" | "addEdge" | "pathPoints";
export const GRID_MM = 10;
export const HIT_PX = 10;

/** The roadmap editor's state: what the tools read and change. The document is the shell's (`history()`). */
export interface RoadmapEditing {
  history(): RoadmapHistory;
  tool: RmTool;
  /** the selected station's id */
  selected: string | null;
  /** the station clicked first in "Add edge" */
  edgeFrom: string | null;
  /** a station being dragged */
  drag: { id: string; moved: boolean } | null;
  /** the edge whose path points are edited (its index) */
  edgeSel: number | null;
  /** a path point being dragged */
  pointDrag: { edge: number; k: number; moved: boolean } | null;
}

export function roadmapEditing(history: () => RoadmapHistory): RoadmapEditing {
  return { history, tool: "select", selected: null, edgeFrom: null, drag: null, edgeSel: null, pointDrag: null };
}

/** What the tools need of the panel. */
export interface RoadmapToolEnv {
  say(text: string): void;
  /** the catalog's words */
  text(key: Key, words?: Record<string, string | number>): string;
  /** the document or the selection changed: redraw and show it */
  refresh(): void;
  /** the fields' station name and angle (degrees), as typed */
  fields(): { name: string; angle: string };
}

/** The view's roadmap (scene/roadmap.ts) of the editor's document. */
export function toScene(doc: RoadmapDoc, name: string): Roadmap {
  return {
    name,
    stations: doc.stations.map((s) => ({ id: s.id, name: s.name, x: s.x, y: s.y, angle: s.angle })),
    edges: doc.edges.map((e) => ({ start: e.start, end: e.end, points: [...e.points] })),
  };
}

/** The station nearest (x, y) within `tol` mm, or null. */
export function stationAt(doc: RoadmapDoc, x: number, y: number, tol: number): string | null {
  let best: string | null = null;
  let bestD = tol;
  for (const s of doc.stations) {
    const d = Math.hypot(s.x - x, s.y - y);
    if (d <= bestD) {
      bestD = d;
      best = s.id;
    }
  }
  return best;
}

export const grid = (v: number): number => Math.round(v / GRID_MM) * GRID_MM;

/**
 * Do an edit named `action` (the history's label: "Undone: add station A"), or say why it cannot be done; then
 * show the document. What is said when done is `done` (e.g. "Station A added"), else "Done: {action}". The
 * reason, or null.
 */
export function run(ed: RoadmapEditing, env: RoadmapToolEnv, edit: Edit, action: Action, done?: string): string | null {
  const why = ed.history().run(edit, action);
  env.say(why ?? done ?? actionMessage("done", action, env.text));
  env.refresh();
  return why;
}

function edgeWords(doc: RoadmapDoc, k: number): { from: string; to: string; n: number } {
  const e = doc.edges[k];
  const nameOf = (id: string): string => doc.stations.find((st) => st.id === id)?.name ?? id;
  return { from: nameOf(e.start), to: nameOf(e.end), n: e.points.length / 2 };
}

/** A path point edit, said as the edge's new path ("Path of A -> B: 2 points"). */
function runPath(ed: RoadmapEditing, env: RoadmapToolEnv, edit: Edit, edge: number): void {
  if (run(ed, env, edit, act("act.pathPoints", edgeWords(ed.history().doc, edge))) === null) {
    env.say(env.text("rm.pathChanged", edgeWords(ed.history().doc, edge)));
  }
}

/** guide 5.5 path points: select an edge, add a point to it, drag a point, right-click deletes it. */
export function pressPathPoints(
  ed: RoadmapEditing,
  env: RoadmapToolEnv,
  x: number,
  y: number,
  pxPerMm: number,
  button: number,
): void {
  const doc = ed.history().doc;
  const tol = HIT_PX / pxPerMm;
  const pp = pathPointAt(doc, x, y, tol);
  if (pp !== null) {
    ed.edgeSel = pp.edge;
    if (button === 2) {
      runPath(ed, env, deletePathPoint(pp.edge, pp.k), pp.edge);
    } else {
      ed.pointDrag = { ...pp, moved: false };
      env.refresh();
    }
    return;
  }
  const k = edgeAt(doc, x, y, tol);
  if (k !== null) {
    ed.edgeSel = k;
    env.say(env.text("rm.edgeSelected", edgeWords(doc, k)));
    env.refresh();
  } else if (ed.edgeSel === null || edgePath(doc, ed.edgeSel) === null) {
    env.say(env.text("rm.noEdge"));
  } else {
    runPath(ed, env, insertPathPoint(ed.edgeSel, grid(x), grid(y)), ed.edgeSel);
  }
}

/** "Add station": at the click on the grid, named from the field (else Station_n), facing the field's angle. */
export function pressAddStation(ed: RoadmapEditing, env: RoadmapToolEnv, x: number, y: number): void {
  const f = env.fields();
  const n = f.name.trim() || `Station_${ed.history().doc.stations.length + 1}`;
  const angle = Number(f.angle || "0");
  run(
    ed,
    env,
    addStation(n, grid(x), grid(y), Number.isFinite(angle) ? angle : 0),
    act("act.addStation", { name: n }),
    env.text("rm.added", { name: n }),
  );
  ed.selected = ed.history().doc.stations.find((s) => s.name === n)?.id ?? ed.selected;
  env.refresh();
}

/** "Add edge": the first click picks a station, the second joins it to another. */
export function pressAddEdge(ed: RoadmapEditing, env: RoadmapToolEnv, x: number, y: number, pxPerMm: number): void {
  const id = stationAt(ed.history().doc, x, y, HIT_PX / pxPerMm);
  if (id === null) {
    return;
  }
  if (ed.edgeFrom === null || ed.edgeFrom === id) {
    ed.edgeFrom = id;
    ed.selected = id;
    env.refresh();
    return;
  }
  const from = ed.edgeFrom;
  ed.edgeFrom = null;
  ed.selected = id;
  run(ed, env, addEdge(from, id), act("act.addEdge"), env.text("rm.edgeAdded"));
}

/** "Select": the station under the pointer, dragged until the release. */
export function pressSelect(ed: RoadmapEditing, env: RoadmapToolEnv, x: number, y: number, pxPerMm: number): void {
  const id = stationAt(ed.history().doc, x, y, HIT_PX / pxPerMm);
  ed.selected = id;
  ed.drag = id === null ? null : { id, moved: false };
  env.refresh();
}

/** Every tool's press. */
export const PRESS: Record<
  RmTool,
  (ed: RoadmapEditing, env: RoadmapToolEnv, x: number, y: number, pxPerMm: number, button: number) => void
> = {
  select: pressSelect,
  addStation: pressAddStation,
  addEdge: pressAddEdge,
  pathPoints: pressPathPoints,
};

/** A drag of a station or a path point has moved (it is placed at the release). */
export function dragMoved(ed: RoadmapEditing): void {
  if (ed.drag !== null) {
    ed.drag.moved = true;
  }
  if (ed.pointDrag !== null) {
    ed.pointDrag.moved = true;
  }
}

/** The release: a moved path point or station placed on the grid where the pointer is. */
export function release(ed: RoadmapEditing, env: RoadmapToolEnv, x: number, y: number): void {
  const pd = ed.pointDrag;
  ed.pointDrag = null;
  if (pd?.moved) {
    runPath(ed, env, movePathPoint(pd.edge, pd.k, grid(x), grid(y)), pd.edge);
  }
  const d = ed.drag;
  ed.drag = null;
  if (d?.moved) {
    run(ed, env, moveStation(d.id, grid(x), grid(y)), act("act.moveStation"), env.text("rm.moved"));
  }
}

/** The edited edge's path with its points boxed ("Path points"), the selected station ringed. */
export function drawEditing(ed: RoadmapEditing, ctx: CanvasRenderingContext2D, cam: Camera): void {
  const doc = ed.history().doc;
  const path = ed.tool === "pathPoints" && ed.edgeSel !== null ? edgePath(doc, ed.edgeSel) : null;
  if (path !== null) {
    ctx.strokeStyle = "#e65100";
    ctx.lineWidth = 3;
    ctx.beginPath();
    for (let i = 0; i + 1 < path.length; i += 2) {
      const [sx, sy] = toScreen(cam, path[i], path[i + 1]);
      if (i === 0) ctx.moveTo(sx, sy);
      else ctx.lineTo(sx, sy);
      if (i > 0 && i + 2 < path.length) ctx.strokeRect(sx - 4, sy - 4, 8, 8);
    }
    ctx.stroke();
    ctx.lineWidth = 1;
  }
  const s = doc.stations.find((x) => x.id === ed.selected);
  if (s !== undefined) {
    const [sx, sy] = toScreen(cam, s.x, s.y);
    ctx.strokeStyle = "#e65100";
    ctx.lineWidth = 3;
    ctx.beginPath();
    ctx.arc(sx, sy, 9, 0, 2 * Math.PI);
    ctx.stroke();
    ctx.lineWidth = 1;
  }
}

/** guide 5.5 "Delete": the selected station (and its edges), one undoable step. */
export function deleteSelected(ed: RoadmapEditing, env: RoadmapToolEnv): void {
  if (ed.selected === null) {
    env.say(env.text("edit.noneSelected"));
    return;
  }
  run(ed, env, deleteStation(ed.selected), act("act.deleteStation"), env.text("rm.deleted"));
  ed.selected = null;
  ed.edgeSel = null;
  env.refresh();
}

/** Typed coordinates of the selected station: x, y (mm), angle (degrees) and its name (kept when empty). */
export function applyTyped(
  ed: RoadmapEditing,
  env: RoadmapToolEnv,
  typed: { name: string; x: string; y: string; angle: string },
): void {
  const id = ed.selected;
  if (id === null) {
    env.say(env.text("edit.noneSelected"));
    return;
  }
  const [x, y, a] = [Number(typed.x), Number(typed.y), Number(typed.angle || "0")];
  if (![x, y, a].every(Number.isFinite)) {
    env.say(env.text("rm.badPose"));
    return;
  }
  const newName = typed.name.trim();
  run(
    ed,
    env,
    (doc) => {
      const s = doc.stations.find((st) => st.id === id);
      if (s === undefined) {
        return `no station ${id}`;
      }
      Object.assign(s, { x, y, angle: a, name: newName || s.name });
      return null;
    },
    act("act.changeStation"),
    env.text("rm.moved"),
  );
}
