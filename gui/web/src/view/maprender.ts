/**
 * Drawing the map document and the roadmap on a Canvas2D (the static layer of the map view).
 *
 * Rules:
 * - `prepare` turns a scene into flat Float64Arrays per kind (`pack`: what goes to the layer worker) and a
 *   SegmentGrid each (`preparePacked`), once per map version.
 * - `drawStatic` culls with the grid (only segments whose box meets the view are visited; none at all when the
 *   view holds the whole map) and batches: one path and one stroke per kind, whatever the number of lines.
 * - Styles are a table. A line's front side (the side the scanner sees, guide 5.4 "The Scanner only recognizes
 *   the 'front' of the line") gets a tick on its left, seen from its first point to its second (erratum E-GUI-002),
 *   once a metre is at least 25 px.
 * - `drawn` counts what the last call drew, per kind: the map view exposes it for tests and assistive tools.
 * - Lines are 1 px wide: the rasterizer's hairline path, about ten times faster than a 1.5 px stroke on 50,000 lines.
 * - Texts (station names, the map's labels) are drawn last, placed without overlap by view/labels.ts (issue 35):
 *   stations first, a label with no free place hidden at that zoom; `labelsOut` gets the boxes drawn.
 * - The same code runs in the layer worker (OffscreenCanvas) and, without workers, on the page.
 */
import { AREA_KINDS, type Bounds, KINDS, LINE_KINDS, type MapScene, sceneBounds } from "../scene/map";
import type { Roadmap } from "../scene/roadmap";
import { type Camera, toScreen, viewBounds } from "./camera";
import { type Box, type LabelIn, type PlacedLabel, placeLabels, SYMBOL_HALF } from "./labels";
import { SegmentGrid } from "./spatial";

export type Ctx2D = CanvasRenderingContext2D | OffscreenCanvasRenderingContext2D;

export interface Style {
  stroke: string;
  width: number;
  dash?: number[];
  fill?: string;
}

export const STYLES: Record<string, Style> = {
  line: { stroke: "#1b1b1b", width: 1 },
  auxline: { stroke: "#8a8a8a", width: 1, dash: [6, 4] },
  linemapped: { stroke: "#1f5fbf", width: 1 },
  auxlinemapped: { stroke: "#7fa7e0", width: 1, dash: [6, 4] },
  reflmark: { stroke: "#e07000", width: 4 },
  circle: { stroke: "#2d6a2d", width: 1.5, fill: "rgba(45,106,45,0.15)" },
  workarea: { stroke: "#3c9a3c", width: 1.5, dash: [10, 5] },
  prohibit: { stroke: "#c62828", width: 1.5, fill: "rgba(198,40,40,0.15)" },
  hiddenpolygon: { stroke: "#8e44ad", width: 1, dash: [3, 3], fill: "rgba(142,68,173,0.06)" },
  hiddenlabel: { stroke: "#4a235a", width: 1 },
  station: { stroke: "#00838f", width: 1.5, fill: "#00acc1" },
  edge: { stroke: "#00acc1", width: 1.5, dash: [4, 3] },
  grid: { stroke: "#e3e3e3", width: 1 },
};

export interface Layers {
  grid: boolean;
  map: boolean;
  roadmap: boolean;
  labels: boolean;
  /** per map kind: false hides it */
  kinds: Record<string, boolean>;
}

/** A line kind's segments and their grid, built when first asked for. */
export class LineEntry {
  private built: SegmentGrid | null = null;

  constructor(
    readonly segs: Float64Array,
    readonly owners: Int32Array,
    private readonly bounds: Bounds,
  ) {}

  get n(): number {
    return this.segs.length / 4;
  }

  get grid(): SegmentGrid {
    this.built ??= new SegmentGrid(this.segs, this.bounds);
    return this.built;
  }
}

export interface Prepared {
  bounds: Bounds | null;
  /**
   * per line kind: the segments, their grid (built at the first query: a view of the whole map needs none, so the
   * first drawing after a load does not wait for it; issue 20), and the object (scene index) each segment came from
   */
  lines: Map<string, LineEntry>;
  others: MapScene["objects"];
  /** each of `others`' scene index */
  othersAt: number[];
  scratch: Uint32Array;
  /** an edit on top of the prepared base (applyPatch): base objects hidden and the edit's objects */
  patch: PreparedPatch | null;
}

/**
 * An edit as the layer worker needs it (issue 20): the base's objects `hideFrom`..`hideTo` are gone, the objects of
 * `added` (packed, few) take their place, and `bounds` are the edited scene's. The base's index is kept.
 */
export interface ScenePatch {
  bounds: Bounds | null;
  hideFrom: number;
  hideTo: number;
  /** the edited scene's objects `hideFrom`..`hideFrom + addedCount`, packed */
  added: PackedScene;
  addedCount: number;
}

export interface PreparedPatch {
  hideFrom: number;
  hideTo: number;
  lines: Map<string, Float64Array>;
}

/**
 * A scene as the layer worker needs it, cheap to send: the line kinds' segments in Float64Arrays (transferred, not
 * copied) and the few other objects as they are. Posting the scene itself structured-clones 50,000 objects, which
 * took the page's thread 100-600 ms per edit (benchmarks/bench_editors.py).
 */
export interface PackedScene {
  bounds: Bounds | null;
  segs: Array<[string, Float64Array]>;
  /** per entry of `segs`: the scene index of each segment's object */
  owners: Int32Array[];
  others: MapScene["objects"];
  othersAt: number[];
  /** objects per kind (scene/map.ts countKinds), counted in the same pass */
  kinds: Record<string, number>;
}

/** The scene packed; `bounds`: its bounds when the caller has them (else computed: a pass over every object). */
export function pack(scene: MapScene, bounds?: Bounds | null): PackedScene {
  const counts = new Map<string, number>();
  const lineKinds = new Set<string>(LINE_KINDS);
  const others: MapScene["objects"] = [];
  const othersAt: number[] = [];
  const objects = scene.objects;
  const perKind: Record<string, number> = {};
  for (const k of KINDS) {
    perKind[k] = 0;
  }
  for (let i = 0; i < objects.length; i++) {
    const o = objects[i];
    perKind[o.kind] = (perKind[o.kind] ?? 0) + 1;
    if (!lineKinds.has(o.kind)) {
      others.push(o);
      othersAt.push(i);
    } else if (o.points.length >= 2) {
      counts.set(o.kind, (counts.get(o.kind) ?? 0) + 1);
    }
  }
  const segs = new Map<string, { a: Float64Array; owner: Int32Array; n: number }>();
  for (const [kind, n] of counts) {
    segs.set(kind, { a: new Float64Array(4 * n), owner: new Int32Array(n), n: 0 });
  }
  for (let i = 0; i < objects.length; i++) {
    const o = objects[i];
    const s = segs.get(o.kind);
    const p = o.points;
    if (s !== undefined && p.length >= 2) {
      s.owner[s.n] = i;
      const k = 4 * s.n++;
      s.a[k] = p[0];
      s.a[k + 1] = p[1];
      s.a[k + 2] = p[p.length >= 4 ? 2 : 0];
      s.a[k + 3] = p[p.length >= 4 ? 3 : 1];
    }
  }
  const kinds = LINE_KINDS.filter((k) => segs.has(k));
  return {
    bounds: bounds === undefined ? sceneBounds(scene) : bounds,
    segs: kinds.map((k) => [k, segs.get(k)!.a]),
    owners: kinds.map((k) => segs.get(k)!.owner),
    others,
    othersAt,
    kinds: perKind,
  };
}

/** A copy of a packed scene's arrays (the page keeps one when the others are transferred to the worker). */
export function copyPacked(p: PackedScene): PackedScene {
  return { ...p, segs: p.segs.map(([k, a]) => [k, a.slice()]), owners: p.owners.map((a) => a.slice()) };
}

/** The transferable buffers of a packed scene (for postMessage). */
export function transfers(p: PackedScene): Transferable[] {
  return [...p.segs.map(([, a]) => a.buffer), ...p.owners.map((a) => a.buffer)];
}

export function preparePacked(p: PackedScene): Prepared {
  const lines = new Map<string, LineEntry>();
  let most = 0;
  p.segs.forEach(([kind, segs], i) => {
    if (segs.length > 0 && p.bounds !== null) {
      lines.set(kind, new LineEntry(segs, p.owners[i], p.bounds));
      most = Math.max(most, segs.length / 4);
    }
  });
  return {
    bounds: p.bounds,
    lines,
    others: p.others,
    othersAt: p.othersAt,
    scratch: new Uint32Array(most),
    patch: null,
  };
}

/**
 * The base with an edit on top (the base's grids and arrays shared, nothing rebuilt): its bounds, its other
 * objects in scene order (the base's before the window, the edit's, the base's after it), its lines drawn by
 * drawStatic from the base minus the hidden objects plus the edit's.
 */
export function applyPatch(base: Prepared, patch: ScenePatch): Prepared {
  const { hideFrom, hideTo, added } = patch;
  const others: MapScene["objects"] = [];
  const othersAt: number[] = [];
  const keep = (from: number, to: number, delta: number): void => {
    base.othersAt.forEach((at, i) => {
      if (at >= from && at < to) {
        others.push(base.others[i]);
        othersAt.push(at + delta);
      }
    });
  };
  keep(0, hideFrom, 0);
  added.others.forEach((o, i) => {
    others.push(o);
    othersAt.push(hideFrom + added.othersAt[i]);
  });
  keep(hideTo, Number.POSITIVE_INFINITY, patch.addedCount - (hideTo - hideFrom));
  return { ...base, bounds: patch.bounds, others, othersAt, patch: { hideFrom, hideTo, lines: new Map(added.segs) } };
}

/** Build every grid now (off the drawing's path: a while after the first layer). */
export function buildGrids(prep: Prepared): void {
  for (const entry of prep.lines.values()) {
    void entry.grid;
  }
}

export function prepare(scene: MapScene): Prepared {
  return preparePacked(pack(scene));
}

function contains(outer: Bounds, inner: Bounds): boolean {
  return outer.minX <= inner.minX && outer.minY <= inner.minY && outer.maxX >= inner.maxX && outer.maxY >= inner.maxY;
}

function meets(a: Bounds, b: Bounds): boolean {
  return a.minX <= b.maxX && a.maxX >= b.minX && a.minY <= b.maxY && a.maxY >= b.minY;
}

/** Segments to draw: `n` of them, `idx[j]` each (all in order when `idx` is null). */
interface SegPart {
  segs: Float64Array;
  idx: Uint32Array | null;
  n: number;
}

/** The base's segments of a kind in view (none when the kind is absent), less those of objects an edit hid. */
function baseSegs(prep: Prepared, kind: string, view: Bounds, whole: boolean): SegPart | null {
  const entry = prep.lines.get(kind);
  if (entry === undefined) {
    return null;
  }
  let n = entry.n;
  let idx: Uint32Array | null = null;
  if (!whole) {
    n = entry.grid.query(view, prep.scratch);
    idx = prep.scratch;
  }
  const p = prep.patch;
  if (p === null || p.hideTo <= p.hideFrom) {
    return { segs: entry.segs, idx, n };
  }
  const out = prep.scratch; // filtered in place: out[m] is written after idx[j] (j >= m) was read
  let m = 0;
  for (let j = 0; j < n; j++) {
    const s = idx === null ? j : idx[j];
    const o = entry.owners[s];
    if (o < p.hideFrom || o >= p.hideTo) {
      out[m++] = s;
    }
  }
  return { segs: entry.segs, idx: out, n: m };
}

/** An edit's segments of a kind whose box meets the view (like SegmentGrid.query, without a grid: they are few). */
export function visibleSegs(segs: Float64Array, view: Bounds, whole: boolean): SegPart {
  const idx = new Uint32Array(segs.length / 4);
  let m = 0;
  for (let s = 0; s < idx.length; s++) {
    const x1 = segs[4 * s],
      y1 = segs[4 * s + 1],
      x2 = segs[4 * s + 2],
      y2 = segs[4 * s + 3];
    if (
      whole ||
      !(
        Math.max(x1, x2) < view.minX ||
        Math.min(x1, x2) > view.maxX ||
        Math.max(y1, y2) < view.minY ||
        Math.min(y1, y2) > view.maxY
      )
    ) {
      idx[m++] = s;
    }
  }
  return { segs, idx, n: m };
}

/** What drawStatic draws of a line kind: the base's part and the edit's (empty when the scene has none). */
export function lineParts(prep: Prepared, kind: string, view: Bounds, whole: boolean): SegPart[] {
  const parts: SegPart[] = [];
  const base = baseSegs(prep, kind, view, whole);
  if (base !== null) {
    parts.push(base);
  }
  const added = prep.patch?.lines.get(kind);
  if (added !== undefined && added.length > 0) {
    parts.push(visibleSegs(added, view, whole));
  }
  return parts;
}

function emitLines(ctx: Ctx2D, { segs, idx, n }: SegPart, ox: number, oy: number, k: number): void {
  for (let j = 0; j < n; j++) {
    const s = idx === null ? j : idx[j];
    ctx.moveTo(ox + segs[4 * s] * k, oy - segs[4 * s + 1] * k);
    ctx.lineTo(ox + segs[4 * s + 2] * k, oy - segs[4 * s + 3] * k);
  }
}

function emitTicks(ctx: Ctx2D, { segs, idx, n }: SegPart, ox: number, oy: number, k: number): void {
  for (let j = 0; j < n; j++) {
    const s = idx === null ? j : idx[j];
    const dx = segs[4 * s + 2] - segs[4 * s];
    const dy = segs[4 * s + 3] - segs[4 * s + 1];
    const len = Math.hypot(dx, dy);
    if (len * k < 16) {
      continue;
    }
    const mx = ox + (segs[4 * s] + dx / 2) * k;
    const my = oy - (segs[4 * s + 1] + dy / 2) * k;
    ctx.moveTo(mx, my);
    ctx.lineTo(mx - (dy / len) * 6, my - (dx / len) * 6); // left normal (-dy, dx), screen y flipped
  }
}

function applyStyle(ctx: Ctx2D, s: Style): void {
  ctx.strokeStyle = s.stroke;
  ctx.lineWidth = s.width;
  ctx.setLineDash(s.dash ?? []);
}

/** Grid lines every 10^k or 5*10^k mm, at least 40 px apart. */
export function gridStep(scale: number): number {
  let step = 1000;
  while (step * scale < 40) {
    step *= step.toString().startsWith("1") ? 5 : 2;
  }
  while (step * scale > 200 && step > 10) {
    step /= step.toString().startsWith("5") ? 5 : 2;
  }
  return step;
}

function drawGrid(ctx: Ctx2D, cam: Camera): void {
  const v = viewBounds(cam);
  const step = gridStep(cam.scale);
  applyStyle(ctx, STYLES.grid);
  ctx.beginPath();
  for (let x = Math.ceil(v.minX / step) * step; x <= v.maxX; x += step) {
    const [sx] = toScreen(cam, x, 0);
    ctx.moveTo(Math.round(sx) + 0.5, 0);
    ctx.lineTo(Math.round(sx) + 0.5, cam.height);
  }
  for (let y = Math.ceil(v.minY / step) * step; y <= v.maxY; y += step) {
    const [, sy] = toScreen(cam, 0, y);
    ctx.moveTo(0, Math.round(sy) + 0.5);
    ctx.lineTo(cam.width, Math.round(sy) + 0.5);
  }
  ctx.stroke();
}

/** the fonts of the labels: a station's name, a map label (hiddenlabel) */
const STATION_FONT = 11;
const LABEL_FONT = 12;
/** px beyond the canvas within which a label's anchor is still placed (its box may reach in) */
const LABEL_REACH = 200;
/** text widths measured, per font and text (cleared when it grows past WIDTHS_MAX) */
const widths = new Map<string, number>();
const WIDTHS_MAX = 20_000;

function textWidth(ctx: Ctx2D, size: number, text: string): number {
  const key = `${size}\u0000${text}`;
  let w = widths.get(key);
  if (w === undefined) {
    if (widths.size >= WIDTHS_MAX) {
      widths.clear();
    }
    ctx.font = `${size}px sans-serif`;
    w = ctx.measureText(text).width;
    widths.set(key, w);
  }
  return w;
}

/** The labels of a layer, gathered while it is drawn, and the station symbols they must leave free. */
class LabelSet {
  readonly labels: LabelIn[] = [];
  readonly obstacles: Box[] = [];

  constructor(
    private readonly ctx: Ctx2D,
    readonly cam: Camera,
  ) {}

  private near(x: number, y: number): boolean {
    return (
      x > -LABEL_REACH && y > -LABEL_REACH && x < this.cam.width + LABEL_REACH && y < this.cam.height + LABEL_REACH
    );
  }

  add(kind: LabelIn["kind"], text: string, ax: number, ay: number): void {
    if (text !== "" && this.near(ax, ay)) {
      const size = kind === "station" ? STATION_FONT : LABEL_FONT;
      this.labels.push({ kind, text, ax, ay, size, w: textWidth(this.ctx, size, text) });
    }
  }

  symbol(x: number, y: number): void {
    if (this.near(x, y)) {
      this.obstacles.push({ x: x - SYMBOL_HALF, y: y - SYMBOL_HALF, w: 2 * SYMBOL_HALF, h: 2 * SYMBOL_HALF });
    }
  }
}

const LABEL_COLOUR: Record<LabelIn["kind"], string> = {
  station: STYLES.station.stroke,
  hiddenlabel: STYLES.hiddenlabel.stroke,
};

/** Place the gathered labels and draw those placed; counts what was drawn and hidden. */
function drawLabels(ctx: Ctx2D, set: LabelSet, drawn: Record<string, number>, out?: PlacedLabel[]): void {
  const { placed, hidden } = placeLabels(set.labels, set.obstacles, set.cam.width, set.cam.height);
  // a white halo under each text keeps it readable over lines (as the fleet's names: panels/map/renderer.ts)
  ctx.setLineDash([]);
  ctx.lineWidth = 3;
  ctx.strokeStyle = "#ffffff";
  for (const l of placed) {
    ctx.font = `${l.kind === "station" ? STATION_FONT : LABEL_FONT}px sans-serif`;
    ctx.strokeText(l.text, l.tx, l.ty);
    ctx.fillStyle = LABEL_COLOUR[l.kind];
    ctx.fillText(l.text, l.tx, l.ty);
  }
  if (set.labels.some((l) => l.kind === "hiddenlabel")) {
    drawn.hiddenlabel = placed.filter((l) => l.kind === "hiddenlabel").length;
  }
  drawn.labels = placed.length;
  drawn.labelsHidden = hidden;
  out?.push(...placed);
}

/**
 * Draw everything static for camera `cam`; returns the number of objects drawn per kind (and `labels`,
 * `labelsHidden`: the texts drawn and those hidden for want of room). `labelsOut` gets the boxes of the texts drawn.
 */
export function drawStatic(
  ctx: Ctx2D,
  cam: Camera,
  prep: Prepared | null,
  roadmap: Roadmap | null,
  layers: Layers,
  labelsOut?: PlacedLabel[],
): Record<string, number> {
  const drawn: Record<string, number> = {};
  const labels = new LabelSet(ctx, cam);
  ctx.fillStyle = "#ffffff";
  ctx.fillRect(0, 0, cam.width, cam.height);
  if (layers.grid) {
    drawGrid(ctx, cam);
  }
  const view = viewBounds(cam);
  const k = cam.scale;
  const ox = cam.width / 2 - cam.cx * k;
  const oy = cam.height / 2 + cam.cy * k;
  if (prep !== null && layers.map) {
    for (const o of prep.others) {
      if (!layers.kinds[o.kind] || o.kind === "circle" || o.kind === "hiddenlabel") {
        continue;
      }
      if (!(AREA_KINDS as readonly string[]).includes(o.kind)) {
        continue;
      }
      const s = STYLES[o.kind];
      applyStyle(ctx, s);
      ctx.beginPath();
      for (let i = 0; i + 1 < o.points.length; i += 2) {
        const x = ox + o.points[i] * k;
        const y = oy - o.points[i + 1] * k;
        if (i === 0) {
          ctx.moveTo(x, y);
        } else {
          ctx.lineTo(x, y);
        }
      }
      ctx.closePath();
      if (s.fill) {
        ctx.fillStyle = s.fill;
        ctx.fill();
      }
      ctx.stroke();
      drawn[o.kind] = (drawn[o.kind] ?? 0) + 1;
    }
    const whole = prep.bounds !== null && contains(view, prep.bounds);
    const ticks = k >= 0.025;
    for (const kind of LINE_KINDS) {
      const parts = layers.kinds[kind] ? lineParts(prep, kind, view, whole) : [];
      if (parts.length === 0) {
        continue;
      }
      applyStyle(ctx, STYLES[kind]);
      ctx.beginPath();
      for (const part of parts) {
        emitLines(ctx, part, ox, oy, k);
      }
      if (ticks && kind !== "reflmark") {
        for (const part of parts) {
          emitTicks(ctx, part, ox, oy, k);
        }
      }
      ctx.stroke();
      drawn[kind] = parts.reduce((n, part) => n + part.n, 0);
    }
    for (const o of prep.others) {
      if (!layers.kinds[o.kind] || o.points.length < 2) {
        continue;
      }
      if (o.kind === "circle") {
        const r = o.r ?? 0;
        if (
          !meets(view, { minX: o.points[0] - r, minY: o.points[1] - r, maxX: o.points[0] + r, maxY: o.points[1] + r })
        ) {
          continue;
        }
        const s = STYLES.circle;
        applyStyle(ctx, s);
        ctx.beginPath();
        ctx.arc(ox + o.points[0] * k, oy - o.points[1] * k, Math.max(r * k, 1.5), 0, 2 * Math.PI);
        ctx.fillStyle = s.fill!;
        ctx.fill();
        ctx.stroke();
        drawn.circle = (drawn.circle ?? 0) + 1;
      } else if (o.kind === "hiddenlabel" && layers.labels) {
        labels.add("hiddenlabel", o.text ?? "", ox + o.points[0] * k, oy - o.points[1] * k);
      }
    }
  }
  if (roadmap !== null && layers.roadmap) {
    drawRoadmap(ctx, { ox, oy, k }, roadmap, drawn, labels);
  }
  drawLabels(ctx, labels, drawn, labelsOut);
  return drawn;
}

function drawRoadmap(
  ctx: Ctx2D,
  { ox, oy, k }: { ox: number; oy: number; k: number },
  rm: Roadmap,
  drawn: Record<string, number>,
  labels: LabelSet,
): void {
  const byId = new Map(rm.stations.map((s) => [s.id, s]));
  applyStyle(ctx, STYLES.edge);
  ctx.beginPath();
  let pathPoints = 0;
  for (const e of rm.edges) {
    const a = byId.get(e.start);
    const b = byId.get(e.end);
    if (a === undefined || b === undefined) {
      continue;
    }
    ctx.moveTo(ox + a.x * k, oy - a.y * k);
    for (let i = 0; i + 1 < e.points.length; i += 2) {
      ctx.lineTo(ox + e.points[i] * k, oy - e.points[i + 1] * k);
    }
    ctx.lineTo(ox + b.x * k, oy - b.y * k);
    pathPoints += e.points.length / 2;
  }
  ctx.stroke();
  ctx.fillStyle = STYLES.edge.stroke;
  for (const e of rm.edges) {
    for (let i = 0; i + 1 < e.points.length; i += 2) {
      ctx.fillRect(ox + e.points[i] * k - 2, oy - e.points[i + 1] * k - 2, 4, 4);
    }
  }
  applyStyle(ctx, STYLES.station);
  for (const s of rm.stations) {
    const x = ox + s.x * k;
    const y = oy - s.y * k;
    ctx.beginPath();
    ctx.arc(x, y, 5, 0, 2 * Math.PI);
    ctx.fillStyle = STYLES.station.fill!;
    ctx.fill();
    ctx.stroke();
    const a = (s.angle * Math.PI) / 180;
    ctx.beginPath();
    ctx.moveTo(x, y);
    ctx.lineTo(x + Math.cos(a) * 12, y - Math.sin(a) * 12);
    ctx.stroke();
    labels.symbol(x, y);
    labels.add("station", s.name, x, y);
  }
  drawn.station = rm.stations.length;
  drawn.edge = rm.edges.length;
  drawn.pathpoint = pathPoints;
}
