/**
 * The map editor's pointer tools beyond "Add a line" (guide 5.4): add a reflector and a circle (drag), the
 * workarea, prohibited zones and hidden polygons (click the vertices; a right-click, a click on the first vertex,
 * Enter or "Finish polygon" closes it; Escape drops it), a label (click), edit vertices (drag a vertex) and the
 * measuring tool (drag; snaps to endpoints only). The geometry is shapes.ts; every result goes through `run` as
 * one command, so a refused object (zero length, no area, no text) says why and changes nothing.
 */
import { type Camera, toScreen } from "../view/camera";
import { addObject, addReplacing, type Command, deleteVertex, insertVertex, moveVertex } from "./commands";
import type { Pt, Result } from "./geometry";
import { act } from "./history";
import type { MapDoc } from "./mapdoc";
import type { MapObject } from "../scene/map";
import {
  circleObject,
  labelObject,
  measure,
  type Measure,
  type NewObject,
  polygonEdgeAt,
  polygonObject,
  type PolygonKind,
  segmentObject,
  vertexAt,
} from "./shapes";

export type ShapeTool = "vertex" | "reflector" | "circle" | PolygonKind | "label" | "measure";
export const SHAPE_TOOLS: readonly ShapeTool[] = [
  "vertex",
  "reflector",
  "circle",
  "workarea",
  "prohibit",
  "hiddenpolygon",
  "label",
  "measure",
];

export interface ToolContext {
  doc(): MapDoc;
  run(r: Result<Command>): void;
  say(s: string): void;
  /** endpoint snap, then the grid */
  snap(p: Pt, pxPerMm: number): Pt;
  /** endpoint snap only (the measuring tool measures what is there) */
  snapEnd(p: Pt, pxPerMm: number): Pt;
  labelText(): string;
  /** the layer new objects go into (the panel's "Layer for new objects", layers.ts) */
  layer(): number;
  /** the objects that may lie within `tol` mm of (x, y), in document order (the history's spatial index) */
  near(x: number, y: number, tol: number): readonly MapObject[];
  selection(): ReadonlySet<number>;
  /** the words of a measurement */
  measured(m: Measure): string;
  /** the grid step, mm (a circle's radius is rounded to it) */
  grid: number;
}

const HIT_PX = 8;
const asCommand = (doc: MapDoc, r: Result<NewObject>): Result<Command> =>
  r.ok ? { ok: true, value: addObject(doc, r.value) } : r;

export class ShapeTools {
  /** the drag in progress (reflector, circle, measure, vertex) */
  private drag: { from: Pt; to: Pt; pxPerMm: number; vertex?: { id: number; vertex: number } } | null = null;
  /** the polygon's vertices so far */
  draft: Pt[] = [];
  /** the last measurement, kept on the view until the next */
  lastMeasure: { a: Pt; b: Pt; m: Measure } | null = null;

  constructor(private readonly c: ToolContext) {}

  cancel(): void {
    this.drag = null;
    this.draft = [];
  }

  down(tool: ShapeTool, x: number, y: number, pxPerMm: number, button: number): void {
    const p = this.c.snap({ x, y }, pxPerMm);
    if (tool === "workarea" || tool === "prohibit" || tool === "hiddenpolygon") {
      this.click(tool, p, pxPerMm, button);
    } else if (tool === "label") {
      this.c.run(asCommand(this.c.doc(), labelObject(p, this.c.labelText(), this.c.layer())));
    } else if (tool === "vertex") {
      this.vertexDown(x, y, pxPerMm, button);
    } else {
      const from = tool === "measure" ? this.c.snapEnd({ x, y }, pxPerMm) : p;
      this.drag = { from, to: from, pxPerMm };
    }
  }

  /**
   * Edit vertices: drag a vertex (of the selection first); right-click a polygon's vertex to delete it; press on a
   * polygon's edge to insert a vertex there and drag it.
   */
  private vertexDown(x: number, y: number, pxPerMm: number, button: number): void {
    const sel = this.c.selection();
    const tol = HIT_PX / pxPerMm;
    const objs = this.c.near(x, y, tol);
    const v = vertexAt(objs, x, y, tol, sel.size > 0 ? sel : null) ?? vertexAt(objs, x, y, tol);
    if (v !== null && button === 2) {
      this.c.run(deleteVertex(this.c.doc(), v.id, v.vertex));
    } else if (v !== null) {
      this.drag = { from: { x, y }, to: { x, y }, pxPerMm, vertex: v };
    } else if (button === 0) {
      const e = polygonEdgeAt(objs, x, y, tol, sel.size > 0 ? sel : null) ?? polygonEdgeAt(objs, x, y, tol);
      if (e === null) {
        return;
      }
      const p = this.c.snap({ x, y }, pxPerMm);
      const r = insertVertex(this.c.doc(), e.id, e.after, p);
      this.c.run(r);
      if (r.ok) {
        this.drag = { from: { x, y }, to: p, pxPerMm, vertex: { id: e.id, vertex: e.after + 1 } };
      }
    }
  }

  private click(kind: PolygonKind, p: Pt, pxPerMm: number, button: number): void {
    const first = this.draft[0];
    const closes =
      first !== undefined && this.draft.length >= 3 && Math.hypot(p.x - first.x, p.y - first.y) <= HIT_PX / pxPerMm;
    if (button === 2 || closes) {
      this.finish(kind);
      return;
    }
    this.draft.push(p);
  }

  /** Close the polygon drawn so far into an object of `kind` (a new workarea replaces the map's old one). */
  finish(kind: PolygonKind): void {
    const r = polygonObject(kind, this.draft, this.c.layer());
    this.draft = [];
    if (!r.ok) {
      this.c.say(r.reason);
      return;
    }
    const doc = this.c.doc();
    const old = kind === "workarea" ? doc.scene.objects.filter((o) => o.kind === "workarea").map((o) => o.id) : [];
    this.c.run({
      ok: true,
      value: old.length > 0 ? addReplacing(doc, r.value, old, act("act.replaceWorkarea")) : addObject(doc, r.value),
    });
  }

  move(tool: ShapeTool, x: number, y: number): void {
    const d = this.drag;
    if (d === null) {
      return;
    }
    d.to = tool === "measure" ? this.c.snapEnd({ x, y }, d.pxPerMm) : this.c.snap({ x, y }, d.pxPerMm);
  }

  up(tool: ShapeTool, x: number, y: number): void {
    const d = this.drag;
    this.drag = null;
    if (d === null) {
      return;
    }
    this.move(tool, x, y);
    const doc = this.c.doc();
    if (tool === "reflector") {
      this.c.run(asCommand(doc, segmentObject("reflmark", d.from, d.to, this.c.layer())));
    } else if (tool === "circle") {
      this.c.run(asCommand(doc, circleObject(d.from, d.to, this.c.grid, this.c.layer())));
    } else if (tool === "measure") {
      const m = measure(d.from, d.to);
      this.lastMeasure = { a: d.from, b: d.to, m };
      this.c.say(this.c.measured(m));
    } else if (tool === "vertex" && d.vertex !== undefined && Math.hypot(x - d.from.x, y - d.from.y) * d.pxPerMm >= 2) {
      this.c.run({ ok: true, value: moveVertex(doc, d.vertex.id, d.vertex.vertex, d.to) });
    }
  }

  draw(ctx: CanvasRenderingContext2D, cam: Camera, tool: ShapeTool): void {
    const line = (pts: Pt[], close = false): void => {
      ctx.beginPath();
      pts.forEach((p, k) => {
        const [sx, sy] = toScreen(cam, p.x, p.y);
        if (k === 0) ctx.moveTo(sx, sy);
        else ctx.lineTo(sx, sy);
      });
      if (close) ctx.closePath();
      ctx.stroke();
    };
    const d = this.drag;
    if (d !== null && tool === "circle") {
      const [sx, sy] = toScreen(cam, d.from.x, d.from.y);
      ctx.beginPath();
      ctx.arc(sx, sy, Math.hypot(d.to.x - d.from.x, d.to.y - d.from.y) * cam.scale, 0, 2 * Math.PI);
      ctx.stroke();
    } else if (d !== null) {
      line([d.from, d.to]);
    }
    if (this.draft.length > 0) {
      line(this.draft);
    }
    if (this.lastMeasure !== null && tool === "measure" && d === null) {
      ctx.setLineDash([6, 4]);
      line([this.lastMeasure.a, this.lastMeasure.b]);
      ctx.setLineDash([]);
    }
  }
}
