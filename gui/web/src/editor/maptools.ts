/**
 * The map editor's state and its tools (guide 5.4), one named function per tool and action, apart from the panel
 * (editpanel.ts builds the DOM and hands these the pointer): "Edit objects" (select, drag to move, click again to
 * go through objects on top of each other), "Add a line", the two-click line operations (trim, extend, make
 * parallel, make orthogonal), and the toolbar's Select all, Delete, Invert, Clear and Convert lines from scan. The
 * other drawing tools are drawtools.ts's ShapeTools, reached through the same table. No DOM and no catalog here:
 * what a tool says goes through `MapToolEnv.text`, so test/maptools.test.ts runs them on a real History.
 */
import type { Key } from "../i18n/i18n";
import type { MapObject } from "../scene/map";
import { type Camera, toScreen } from "../view/camera";
import {
  addObject,
  addObjects,
  clearMap,
  type Command,
  deleteObjects,
  type History,
  invertLine,
  lineOp,
  moveObjects,
  setGeometry,
} from "./commands";
import { SHAPE_TOOLS, type ShapeTool, type ShapeTools } from "./drawtools";
import { LINE_LEN_DEFAULTS, linesFromScan, type ScanStatus } from "./fromscan";
import { clean, extend, orthogonal, parallel, type Pt, type Result, type Seg, snap, trim } from "./geometry";
import { objectsAt } from "./shapes";
import { act, actionMessage } from "./history";
import { applyFields, type Fields } from "./typed";

export type RefTool = "trim" | "extend" | "parallel" | "orthogonal";
export type EditTool = "select" | "addLine" | RefTool | ShapeTool;
export const isShape = (t: EditTool): t is ShapeTool => (SHAPE_TOOLS as readonly string[]).includes(t);
export const GRID_MM = 10;
export const SNAP_PX = 8;

/** The map editor's state: what the tools read and change. The document is the shell's (`history()`). */
export interface MapEditing {
  history(): History;
  tool: EditTool;
  selected: number | null;
  /** several objects selected at once (Select all); empty: the selection is `selected` alone */
  many: Set<number>;
  /** the drag of "Edit objects" or "Add a line" */
  drag: { from: Pt; to: Pt; pxPerMm: number } | null;
  /** the objects under the last press of "Edit objects", and whether it pressed the one already selected */
  under: { ids: number[]; again: boolean };
  /** the line clicked first in a two-click tool, and where it was clicked (trim keeps that side) */
  first: { id: number; at: Pt } | null;
}

export function mapEditing(history: () => History): MapEditing {
  return {
    history,
    tool: "select",
    selected: null,
    many: new Set(),
    drag: null,
    under: { ids: [], again: false },
    first: null,
  };
}

/** What the tools need of the panel. */
export interface MapToolEnv {
  say(text: string): void;
  /** the catalog's words */
  text(key: Key, words?: Record<string, string | number>): string;
  /** the document or the selection changed: redraw and show it */
  refresh(): void;
  /** the layer new objects go into (layers.ts) */
  layer(): number;
  /** the drawing tools (reflector, circle, polygons, label, vertices, measure) */
  shapes: ShapeTools;
}

/** The selected objects: the many of Select all, else the one selected, else none. */
export function selection(ed: MapEditing): Set<number> {
  return ed.many.size > 0 ? ed.many : new Set(ed.selected === null ? [] : [ed.selected]);
}

/** Drop the selection (a new document, a delete, a clear). */
export function deselect(ed: MapEditing): void {
  ed.selected = null;
  ed.many = new Set();
}

/**
 * Do a command and say it (`done`, else its action: "Done: add a line"), or say why it cannot be done; then show
 * the document.
 */
export function run(ed: MapEditing, env: MapToolEnv, r: Result<Command>, done?: string): void {
  if (r.ok) {
    ed.history().run(r.value);
    env.say(done ?? actionMessage("done", r.value.label, env.text));
  } else {
    env.say(r.reason);
  }
  env.refresh();
}

/**
 * The object under (x, y) within `tol` mm: the nearest line or vertex (the later on a tie); null when none. The
 * objects near the point come from the history's spatial index (objindex.ts), in document order.
 */
export function hit(h: History, x: number, y: number, tol: number): number | null {
  return objectsAt(h.near(x, y, tol), x, y, tol)[0] ?? null;
}

/** the endpoints of the objects within `r` mm of `p` (those the endpoint snap can pick), in document order */
function endpoints(h: History, p: Pt, r: number): Pt[] {
  const out: Pt[] = [];
  for (const o of h.near(p.x, p.y, r)) {
    for (let i = 0; i + 1 < o.points.length; i += 2) {
      out.push({ x: o.points[i], y: o.points[i + 1] });
    }
  }
  return out;
}

/** (x, y) snapped to an endpoint within SNAP_PX on screen, else to `grid` mm (0: endpoints only). */
export function snapped(h: History, p: Pt, pxPerMm: number, grid = GRID_MM): Pt {
  return snap(p, endpoints(h, p, SNAP_PX / pxPerMm), SNAP_PX / pxPerMm, grid);
}

function nearer(s: Seg, p: Pt): "a" | "b" {
  return Math.hypot(p.x - s.a.x, p.y - s.a.y) <= Math.hypot(p.x - s.b.x, p.y - s.b.y) ? "a" : "b";
}

const REF_OPS: Record<RefTool, (s: Seg, r: Seg, at: Pt) => Result<Seg>> = {
  trim: (s, r, at) => trim(s, r, at),
  extend: (s, r) => extend(s, r),
  // guide 5.4 "Make lines parallel": turned about the end farther from the click (the click grabs the end to move)
  parallel: (s, r, at) => parallel(s, r, nearer(s, at) === "a" ? "b" : "a"),
  orthogonal: (s, r, at) => orthogonal(s, r, nearer(s, at) === "a" ? "b" : "a"),
};

/**
 * "Edit objects", press: keeps the selected object when it is among those under the pointer (to drag it); a
 * click that does not move goes on to the next of them at release (objects on top of each other: a wall on a
 * polygon's edge).
 */
export function pressSelect(ed: MapEditing, env: MapToolEnv, x: number, y: number, pxPerMm: number): void {
  const h = ed.history();
  const tol = SNAP_PX / pxPerMm;
  const ids = objectsAt(h.near(x, y, tol), x, y, tol);
  const again = ed.many.size === 0 && ed.selected !== null && ids.includes(ed.selected);
  ed.under = { ids, again };
  const id = again ? ed.selected : (ids[0] ?? null);
  if (id === null || !ed.many.has(id)) {
    ed.many = new Set();
    ed.selected = id;
  }
  env.refresh();
  ed.drag = { from: { x, y }, to: snapped(h, { x, y }, pxPerMm), pxPerMm };
}

export function dragSelect(ed: MapEditing, _env: MapToolEnv, x: number, y: number): void {
  if (ed.drag !== null) {
    ed.drag.to = { x, y };
  }
}

/** "Edit objects", release: the selection moved by the drag on the grid, or the next object under a still click. */
export function releaseSelect(ed: MapEditing, env: MapToolEnv, x: number, y: number): void {
  const d = ed.drag;
  ed.drag = null;
  if (d === null || selection(ed).size === 0) {
    return;
  }
  const dx = Math.round((x - d.from.x) / GRID_MM) * GRID_MM;
  const dy = Math.round((y - d.from.y) / GRID_MM) * GRID_MM;
  const { ids, again } = ed.under;
  if (dx !== 0 || dy !== 0) {
    run(ed, env, { ok: true, value: moveObjects(ed.history().doc, selection(ed), dx, dy) });
  } else if (again && ids.length > 1 && Math.hypot(x - d.from.x, y - d.from.y) * d.pxPerMm < 3) {
    ed.selected = ids[(ids.indexOf(ed.selected as number) + 1) % ids.length];
    env.refresh();
  }
}

/** "Add a line": press at one end (snapped to an endpoint, else the grid). */
export function pressAddLine(ed: MapEditing, _env: MapToolEnv, x: number, y: number, pxPerMm: number): void {
  const p = snapped(ed.history(), { x, y }, pxPerMm);
  ed.drag = { from: p, to: p, pxPerMm };
}

export function dragAddLine(ed: MapEditing, _env: MapToolEnv, x: number, y: number): void {
  if (ed.drag !== null) {
    ed.drag.to = snapped(ed.history(), { x, y }, ed.drag.pxPerMm);
  }
}

/** "Add a line": release at the other end; a line of zero length is refused. */
export function releaseAddLine(ed: MapEditing, env: MapToolEnv): void {
  const d = ed.drag;
  ed.drag = null;
  if (d === null) {
    return;
  }
  if (Math.hypot(d.to.x - d.from.x, d.to.y - d.from.y) < 1) {
    env.say("the line has zero length");
    return;
  }
  const points = [d.from.x, d.from.y, d.to.x, d.to.y].map(clean);
  const doc = ed.history().doc;
  run(ed, env, { ok: true, value: addObject(doc, { kind: "line", layer: env.layer(), points, attrs: {} }) });
}

/** Trim, extend, make parallel, make orthogonal: the first click picks the line, the second its reference. */
export function pressLineOp(ed: MapEditing, env: MapToolEnv, x: number, y: number, pxPerMm: number): void {
  const tool = ed.tool as RefTool;
  const h = ed.history();
  const id = hit(h, x, y, SNAP_PX / pxPerMm);
  if (id === null) {
    return;
  }
  if (ed.first === null || ed.first.id === id) {
    ed.first = { id, at: { x, y } };
    ed.selected = id;
    env.refresh();
    return;
  }
  const f = ed.first;
  const op = REF_OPS[tool];
  ed.first = null;
  run(
    ed,
    env,
    lineOp(h.doc, act(`act.${tool}`), (s, r) => op(s, r, f.at), f.id, id),
  );
}

/** A tool's pointer handlers (world mm; `button` 0 left, 2 right). */
export interface PointerTool {
  down(ed: MapEditing, env: MapToolEnv, x: number, y: number, pxPerMm: number, button: number): void;
  move(ed: MapEditing, env: MapToolEnv, x: number, y: number): void;
  up(ed: MapEditing, env: MapToolEnv, x: number, y: number): void;
}

const SELECT: PointerTool = { down: pressSelect, move: dragSelect, up: releaseSelect };
const ADD_LINE: PointerTool = { down: pressAddLine, move: dragAddLine, up: releaseAddLine };
const LINE_OP: PointerTool = {
  down: pressLineOp,
  move: () => undefined,
  up: (ed) => {
    ed.drag = null;
  },
};
const SHAPE: PointerTool = {
  down: (ed, env, x, y, pxPerMm, button) => env.shapes.down(ed.tool as ShapeTool, x, y, pxPerMm, button),
  move: (ed, env, x, y) => env.shapes.move(ed.tool as ShapeTool, x, y),
  up: (ed, env, x, y) => env.shapes.up(ed.tool as ShapeTool, x, y),
};

/** Every tool's pointer handlers. */
export const POINTER: Record<EditTool, PointerTool> = {
  select: SELECT,
  addLine: ADD_LINE,
  trim: LINE_OP,
  extend: LINE_OP,
  parallel: LINE_OP,
  orthogonal: LINE_OP,
  vertex: SHAPE,
  reflector: SHAPE,
  circle: SHAPE,
  workarea: SHAPE,
  prohibit: SHAPE,
  hiddenpolygon: SHAPE,
  label: SHAPE,
  measure: SHAPE,
};

/** The selection (orange, vertices boxed in "Edit vertices"), the drawing tool's draft and the line being added. */
export function drawEditing(ed: MapEditing, env: MapToolEnv, ctx: CanvasRenderingContext2D, cam: Camera): void {
  ctx.strokeStyle = "#e65100";
  ctx.lineWidth = 3;
  const h = ed.history();
  const sel = selection(ed);
  // a few selected: looked up by id (no pass over 50,000 objects per frame); many: in document order
  const drawn: Array<MapObject | undefined> =
    sel.size > 16 ? h.doc.scene.objects.filter((o) => sel.has(o.id)) : [...sel].map((id) => h.byId(id));
  for (const o of drawn) {
    if (o === undefined || o.points.length < 2) {
      continue;
    }
    ctx.beginPath();
    for (let i = 0; i + 1 < o.points.length; i += 2) {
      const [sx, sy] = toScreen(cam, o.points[i], o.points[i + 1]);
      if (i === 0) ctx.moveTo(sx, sy);
      else ctx.lineTo(sx, sy);
      if (ed.tool === "vertex") ctx.strokeRect(sx - 3, sy - 3, 6, 6);
    }
    if (o.points.length > 4 && o.kind !== "line") ctx.closePath();
    ctx.stroke();
  }
  if (isShape(ed.tool)) {
    env.shapes.draw(ctx, cam, ed.tool);
  }
  if (ed.drag !== null && ed.tool === "addLine") {
    const [x0, y0] = toScreen(cam, ed.drag.from.x, ed.drag.from.y);
    const [x1, y1] = toScreen(cam, ed.drag.to.x, ed.drag.to.y);
    ctx.beginPath();
    ctx.moveTo(x0, y0);
    ctx.lineTo(x1, y1);
    ctx.stroke();
  }
  ctx.lineWidth = 1;
}

/** guide 5.4 "Select all objects in map" (the tool becomes "Edit objects": the panel presses it). */
export function selectAll(ed: MapEditing): void {
  ed.many = new Set(ed.history().doc.scene.objects.map((o) => o.id));
  ed.selected = null;
}

/** guide 5.4 "Delete the selected objects", one undoable step. */
export function deleteSelection(ed: MapEditing, env: MapToolEnv): void {
  const ids = selection(ed);
  if (ids.size === 0) {
    env.say(env.text("edit.noneSelected"));
    return;
  }
  deselect(ed);
  run(ed, env, { ok: true, value: deleteObjects(ed.history().doc, ids) });
}

/** guide 5.4 "Invert the direction of the selected line": its front turns to the other side. */
export function invertSelected(ed: MapEditing, env: MapToolEnv): void {
  if (ed.selected === null) {
    env.say(env.text("edit.noneSelected"));
    return;
  }
  run(ed, env, invertLine(ed.history().doc, ed.selected));
}

/** guide 5.4 "Clear the map": every object removed in one undoable step (what the editor does not know stays). */
export function clearAll(ed: MapEditing, env: MapToolEnv): void {
  deselect(ed);
  run(ed, env, { ok: true, value: clearMap(ed.history().doc) });
}

/**
 * guide 5.4 "Convert lines from the current laser scan": the scan of the last GET_STATUS, the line lengths of the
 * platform's MinLineLenAux and MinLineLenMap (their defaults when not read), one undoable step.
 */
export function convertScan(
  ed: MapEditing,
  env: MapToolEnv,
  status: ScanStatus | undefined,
  params: ReadonlyArray<{ key: string; value: string }>,
): void {
  if (status === undefined || status.scan.length === 0) {
    env.say(env.text("edit.noScan"));
    return;
  }
  const lens = { ...LINE_LEN_DEFAULTS };
  for (const p of params) {
    if ((p.key === "MinLineLenAux" || p.key === "MinLineLenMap") && Number.isFinite(Number(p.value))) {
      lens[p.key] = Number(p.value);
    }
  }
  const objs = linesFromScan(status, lens, env.layer());
  if (objs.length === 0) {
    env.say(env.text("edit.noLines"));
    return;
  }
  const value = addObjects(ed.history().doc, objs, act("act.fromScan", { n: objs.length }));
  run(ed, env, { ok: true, value }, env.text("edit.converted", { n: objs.length }));
}

/** Typed coordinates (typed.ts) of the one selected object: mm and degrees, one undoable step. */
export function typeCoordinates(ed: MapEditing, env: MapToolEnv, input: Fields, shown: Fields): void {
  const h = ed.history();
  const o = h.byId(ed.selected);
  if (o === undefined || ed.many.size > 0) {
    env.say(env.text("edit.noneSelected"));
    return;
  }
  const g = applyFields(o, shown, input);
  run(ed, env, g.ok ? { ok: true, value: setGeometry(h.doc, o.id, g.value) } : g);
}
