/**
 * The map editor's object tools as pure functions (guide 5.4): a reflector, a circle, the workarea, prohibited
 * zones, hidden polygons and labels built from what the pointer gave; the vertex under the pointer; the
 * measuring tool. Plain data in, a new object (without its id) or the reason there is none out: the caller turns
 * it into a command (commands.ts), so a refused object changes nothing.
 *
 * Each object is built to the project's XSD (spec/schemas/map.xsd): a <reflmark> has two points, a <circle> a
 * center and a radius >= 0, a <workarea> and a <prohibit> >= 2 points, a <hiddenpolygon> >= 3, a <hiddenlabel>
 * one point and its `text`. The editor asks for 3 vertices of every polygon (an area of two points has none).
 */
import type { MapObject } from "../scene/map";
import { clean, EPS, type Pt, type Result } from "./geometry";

export type NewObject = Omit<MapObject, "id">;
export type PolygonKind = "workarea" | "prohibit" | "hiddenpolygon";
export const POLYGON_KINDS: readonly PolygonKind[] = ["workarea", "prohibit", "hiddenpolygon"];

/** E-XML-025: the coordinates the telegrams carry (the XSD's `millimetres`). */
export const MAX_MM = 2147483647;

const ok = <T>(value: T): Result<T> => ({ ok: true, value });
const fail = <T>(reason: string): Result<T> => ({ ok: false, reason });

function outOfRange(values: readonly number[]): string | null {
  const bad = values.find((v) => !Number.isFinite(v) || Math.abs(v) > MAX_MM);
  return bad === undefined ? null : `${bad} mm is outside the map's range (±${MAX_MM} mm)`;
}

/** A two-point object: a line (guide 5.4 "Add a line") or a reflector ("drag to draw a reflector line"). */
export function segmentObject(kind: "line" | "reflmark", a: Pt, b: Pt, layer = 0): Result<NewObject> {
  if (Math.hypot(b.x - a.x, b.y - a.y) < EPS) {
    return fail(kind === "line" ? "the line has zero length" : "the reflector has zero length");
  }
  const points = [a.x, a.y, b.x, b.y].map(clean);
  const bad = outOfRange(points);
  return bad !== null ? fail(bad) : ok({ kind, layer, points, attrs: {} });
}

/**
 * guide 5.4 "Add a circle. Left-click to begin and drag to draw a circle": centered where the drag began, through
 * where it ended; the radius is rounded to `step` mm (the editor's grid), at least one step.
 */
export function circleObject(center: Pt, edge: Pt, step: number, layer = 0): Result<NewObject> {
  const d = Math.hypot(edge.x - center.x, edge.y - center.y);
  const r = step > 0 ? Math.round(d / step) * step : clean(d);
  if (r < EPS) {
    return fail("the circle has zero radius: drag away from its center");
  }
  const points = [clean(center.x), clean(center.y)];
  const bad = outOfRange([...points, r]);
  return bad !== null ? fail(bad) : ok({ kind: "circle", layer, points, r: clean(r), attrs: {} });
}

/** Twice the signed area of a polygon (x0, y0, x1, y1, ...). */
export function signedArea2(points: readonly number[]): number {
  let s = 0;
  const n = points.length;
  for (let i = 0; i + 1 < n; i += 2) {
    const j = (i + 2) % n;
    s += points[i] * points[j + 1] - points[j] * points[i + 1];
  }
  return s;
}

/**
 * A polygon from the clicked vertices (guide 5.4: the workarea, prohibited zones, hidden polygons). Repeated
 * clicks on one spot count once, and a last click on the first vertex closes the polygon rather than adding one.
 */
export function polygonObject(kind: PolygonKind, clicks: readonly Pt[], layer = 0): Result<NewObject> {
  const pts: Pt[] = [];
  for (const p of clicks) {
    const last = pts[pts.length - 1];
    if (last === undefined || Math.hypot(p.x - last.x, p.y - last.y) >= EPS) {
      pts.push({ x: clean(p.x), y: clean(p.y) });
    }
  }
  if (pts.length > 1 && Math.hypot(pts[0].x - pts[pts.length - 1].x, pts[0].y - pts[pts.length - 1].y) < EPS) {
    pts.pop();
  }
  if (pts.length < 3) {
    return fail(`a polygon needs 3 vertices or more (got ${pts.length})`);
  }
  const points = pts.flatMap((p) => [p.x, p.y]);
  if (Math.abs(signedArea2(points)) < EPS) {
    return fail("the polygon has no area: its vertices lie on one line");
  }
  const bad = outOfRange(points);
  return bad !== null ? fail(bad) : ok({ kind, layer, points, attrs: {} });
}

/** guide 5.4 "Insert a label": a <hiddenlabel> with its text at one point. */
export function labelObject(p: Pt, text: string, layer = 0): Result<NewObject> {
  const words = text.trim();
  if (words === "") {
    return fail("a label needs a text: type it in the label field first");
  }
  const points = [clean(p.x), clean(p.y)];
  const bad = outOfRange(points);
  return bad !== null ? fail(bad) : ok({ kind: "hiddenlabel", layer, points, text: words, attrs: { text: words } });
}

/**
 * The vertex under (x, y) within `tol` mm (guide 5.4 "Edit vertices of a polygon"): the nearest vertex of the
 * objects in `ids` (all objects when `ids` is null). Null when none is that near.
 */
export function vertexAt(
  objects: readonly MapObject[],
  x: number,
  y: number,
  tol: number,
  ids: ReadonlySet<number> | null = null,
): { id: number; vertex: number } | null {
  let best: { id: number; vertex: number } | null = null;
  let bestD = tol;
  for (const o of objects) {
    if (ids !== null && !ids.has(o.id)) {
      continue;
    }
    for (let i = 0; i + 1 < o.points.length; i += 2) {
      const d = Math.hypot(o.points[i] - x, o.points[i + 1] - y);
      if (d <= bestD) {
        bestD = d;
        best = { id: o.id, vertex: i / 2 };
      }
    }
  }
  return best;
}

export interface Measure {
  distance: number;
  dx: number;
  dy: number;
  /** direction from the first point to the second, degrees counter-clockwise from +x, (-180, 180] */
  angle: number;
}

/** The measuring tool: distance (mm) and direction (degrees) from `a` to `b`, rounded to 0.1. */
export function measure(a: Pt, b: Pt): Measure {
  const r = (v: number): number => {
    const k = Math.round(v * 10) / 10;
    return k === 0 ? 0 : k;
  };
  const dx = b.x - a.x;
  const dy = b.y - a.y;
  const angle = dx === 0 && dy === 0 ? 0 : (Math.atan2(dy, dx) * 180) / Math.PI;
  return { distance: r(Math.hypot(dx, dy)), dx: r(dx), dy: r(dy), angle: r(angle === -180 ? 180 : angle) };
}

/**
 * The polygon edge under (x, y) within `tol` mm, of the objects in `ids` (all when null) of a polygon kind:
 * the object and the vertex the edge starts at (the new vertex goes after it). Null when none.
 */
export function polygonEdgeAt(
  objects: readonly MapObject[],
  x: number,
  y: number,
  tol: number,
  ids: ReadonlySet<number> | null = null,
): { id: number; after: number } | null {
  let best: { id: number; after: number } | null = null;
  let bestD = tol;
  for (const o of objects) {
    if (!(POLYGON_KINDS as readonly string[]).includes(o.kind) || (ids !== null && !ids.has(o.id))) {
      continue;
    }
    const p = o.points;
    for (let i = 0; i + 1 < p.length; i += 2) {
      const j = (i + 2) % p.length;
      const len2 = (p[j] - p[i]) ** 2 + (p[j + 1] - p[i + 1]) ** 2;
      const u =
        len2 === 0
          ? 0
          : Math.max(0, Math.min(1, ((x - p[i]) * (p[j] - p[i]) + (y - p[i + 1]) * (p[j + 1] - p[i + 1])) / len2));
      const d = Math.hypot(x - (p[i] + u * (p[j] - p[i])), y - (p[i + 1] + u * (p[j + 1] - p[i + 1])));
      if (d <= bestD) {
        bestD = d;
        best = { id: o.id, after: i / 2 };
      }
    }
  }
  return best;
}

/** Distance from (x, y) to the outline of `o` (its segments, closed when it has 3 points or more; a circle's rim). */
function outlineDistance(o: MapObject, x: number, y: number): number {
  const p = o.points;
  let best = Number.POSITIVE_INFINITY;
  for (let i = 0; i + 1 < p.length; i += 2) {
    const n = p.length >= 4 ? (i + 2) % p.length : i;
    const [ax, ay, bx, by] = [p[i], p[i + 1], p[n], p[n + 1]];
    const len2 = (bx - ax) ** 2 + (by - ay) ** 2;
    const u = len2 === 0 ? 0 : Math.max(0, Math.min(1, ((x - ax) * (bx - ax) + (y - ay) * (by - ay)) / len2));
    best = Math.min(best, Math.abs(Math.hypot(x - (ax + u * (bx - ax)), y - (ay + u * (by - ay))) - (o.r ?? 0)));
  }
  return best;
}

/**
 * The objects whose outline passes within `tol` mm of (x, y), nearest first; on a tie the later in the document
 * first (it is drawn on top). "Edit objects" selects the first and cycles through the rest on further clicks.
 */
export function objectsAt(objects: readonly MapObject[], x: number, y: number, tol: number): number[] {
  const near: Array<{ id: number; d: number; k: number }> = [];
  objects.forEach((o, k) => {
    const d = outlineDistance(o, x, y);
    if (d <= tol) {
      near.push({ id: o.id, d, k });
    }
  });
  return near.sort((a, b) => a.d - b.d || b.k - a.k).map((e) => e.id);
}
