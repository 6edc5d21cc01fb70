/**
 * Pure geometry of the map editor (guide 5.4 "Edit Map"): trim, extend, parallel, orthogonal, invert, snapping.
 * Plain data in, plain data out, no DOM and no document: a command (commands.ts) applies the result.
 *
 * Coordinates are mm. A line runs from `a` to `b`; its front, the side the scanner sees (guide 5.4: "The
 * Scanner only recognizes the 'front' of the line"), is on the left of a -> b (erratum E-GUI-002, as the map
 * view draws it). Results are rounded to 1e-6 mm so that exact inputs give exact outputs.
 *
 * An operation with no solution returns `{ ok: false, reason }` in words and computes nothing else: the caller
 * keeps its document as it was.
 */

export interface Pt {
  x: number;
  y: number;
}

export interface Seg {
  a: Pt;
  b: Pt;
}

export type Result<T> = { ok: true; value: T } | { ok: false; reason: string };

/** Below this (mm) a length is zero and two directions are parallel. */
export const EPS = 1e-6;

const ok = <T>(value: T): Result<T> => ({ ok: true, value });
const fail = <T>(reason: string): Result<T> => ({ ok: false, reason });

/** Round to 1e-6 mm (and never -0), so exact inputs give exact outputs. */
export function clean(v: number): number {
  const r = Math.round(v * 1e6) / 1e6;
  return r === 0 ? 0 : r;
}

const pt = (x: number, y: number): Pt => ({ x: clean(x), y: clean(y) });

export function length(s: Seg): number {
  return Math.hypot(s.b.x - s.a.x, s.b.y - s.a.y);
}

function zeroLength(s: Seg, what: string): string | null {
  return length(s) < EPS ? `the ${what} has zero length` : null;
}

/**
 * Where the infinite lines through `s` and `r` cross: t along s (0 at a, 1 at b) and u along r. Null when
 * parallel (or either has zero length).
 */
export function crossing(s: Seg, r: Seg): { t: number; u: number; p: Pt } | null {
  const dx = s.b.x - s.a.x;
  const dy = s.b.y - s.a.y;
  const ex = r.b.x - r.a.x;
  const ey = r.b.y - r.a.y;
  const den = dx * ey - dy * ex;
  if (Math.abs(den) < EPS * Math.hypot(dx, dy) * Math.hypot(ex, ey) || den === 0) {
    return null;
  }
  const wx = r.a.x - s.a.x;
  const wy = r.a.y - s.a.y;
  const t = (wx * ey - wy * ex) / den;
  const u = (wx * dy - wy * dx) / den;
  return { t, u, p: pt(s.a.x + t * dx, s.a.y + t * dy) };
}

/** The reference must be met within its own extent (a tolerance of EPS mm at its ends). */
function onRef(u: number, r: Seg): boolean {
  const tol = EPS / Math.max(length(r), EPS);
  return u >= -tol && u <= 1 + tol;
}

function precheck(s: Seg, r: Seg): string | null {
  return zeroLength(s, "line") ?? zeroLength(r, "reference line");
}

/**
 * Trim `s` where it crosses `r` (guide 5.4: "Trim a line in respect of another line"). The piece on the side of
 * `keep` (the point the user clicked on the line) stays; without `keep`, the longer piece stays.
 */
export function trim(s: Seg, r: Seg, keep?: Pt): Result<Seg> {
  const bad = precheck(s, r);
  if (bad !== null) {
    return fail(bad);
  }
  const c = crossing(s, r);
  if (c === null) {
    return fail("the lines are parallel: they never cross");
  }
  const tol = EPS / length(s);
  if (c.t <= tol || c.t >= 1 - tol) {
    return fail("the reference line does not cross the line between its ends: nothing to trim");
  }
  if (!onRef(c.u, r)) {
    return fail("the line crosses the reference line's extension, not the reference line itself");
  }
  let keepA: boolean;
  if (keep === undefined) {
    keepA = c.t >= 0.5;
  } else {
    const k = ((keep.x - s.a.x) * (s.b.x - s.a.x) + (keep.y - s.a.y) * (s.b.y - s.a.y)) / length(s) ** 2;
    keepA = k < c.t;
  }
  return ok(keepA ? { a: pt(s.a.x, s.a.y), b: c.p } : { a: c.p, b: pt(s.b.x, s.b.y) });
}

/**
 * Extend `s` to `r` (guide 5.4: "Extend a line to reach another line"): the end nearer the crossing moves onto
 * it. The crossing must lie beyond that end and on the reference line itself.
 */
export function extend(s: Seg, r: Seg): Result<Seg> {
  const bad = precheck(s, r);
  if (bad !== null) {
    return fail(bad);
  }
  const c = crossing(s, r);
  if (c === null) {
    return fail("the lines are parallel: the line never reaches the reference line");
  }
  const tol = EPS / length(s);
  if (c.t > -tol && c.t < 1 + tol) {
    return fail("the line already reaches the reference line: trim it instead");
  }
  if (!onRef(c.u, r)) {
    return fail("the line's extension passes the reference line's end: it never meets the reference line");
  }
  return ok(c.t > 1 ? { a: pt(s.a.x, s.a.y), b: c.p } : { a: c.p, b: pt(s.b.x, s.b.y) });
}

export type Anchor = "a" | "b";

/**
 * Turn `s` about its `anchor` end onto direction (ux, uy) or its opposite, whichever is nearer the line's own
 * direction (so the front stays roughly where it was); the length stays.
 */
function turnTo(s: Seg, ux: number, uy: number, anchor: Anchor): Seg {
  const len = length(s);
  const dx = s.b.x - s.a.x;
  const dy = s.b.y - s.a.y;
  const sign = dx * ux + dy * uy < 0 ? -1 : 1;
  const vx = sign * ux * len;
  const vy = sign * uy * len;
  return anchor === "a"
    ? { a: pt(s.a.x, s.a.y), b: pt(s.a.x + vx, s.a.y + vy) }
    : { a: pt(s.b.x - vx, s.b.y - vy), b: pt(s.b.x, s.b.y) };
}

function unit(r: Seg): [number, number] {
  const len = length(r);
  return [(r.b.x - r.a.x) / len, (r.b.y - r.a.y) / len];
}

/** Make `s` parallel to `r` (guide 5.4 "Make lines parallel"), turning it about its `anchor` end. */
export function parallel(s: Seg, r: Seg, anchor: Anchor = "a"): Result<Seg> {
  const bad = precheck(s, r);
  if (bad !== null) {
    return fail(bad);
  }
  const [ux, uy] = unit(r);
  return ok(turnTo(s, ux, uy, anchor));
}

/** Make `s` orthogonal to `r` (guide 5.4 "Make lines orthogonal"), turning it about its `anchor` end. */
export function orthogonal(s: Seg, r: Seg, anchor: Anchor = "a"): Result<Seg> {
  const bad = precheck(s, r);
  if (bad !== null) {
    return fail(bad);
  }
  const [ux, uy] = unit(r);
  return ok(turnTo(s, -uy, ux, anchor));
}

/** Swap the ends (guide 5.4 "Invert direction of the line"): the front moves to the other side. */
export function invert(s: Seg): Result<Seg> {
  const bad = zeroLength(s, "line");
  if (bad !== null) {
    return fail(bad);
  }
  return ok({ a: { ...s.b }, b: { ...s.a } });
}

/** The unit normal on the front of `s`: the side the scanner sees (for drawing the front). */
export function frontNormal(s: Seg): Result<Pt> {
  const bad = zeroLength(s, "line");
  if (bad !== null) {
    return fail(bad);
  }
  const [ux, uy] = unit(s);
  return ok(pt(-uy, ux));
}

/** Snap to the nearest grid point (grid step in mm; a step <= 0 leaves the point alone). */
export function snapToGrid(p: Pt, step: number): Pt {
  if (!(step > 0)) {
    return { ...p };
  }
  return pt(Math.round(p.x / step) * step, Math.round(p.y / step) * step);
}

/**
 * Snap to the nearest of `candidates` (the endpoints of the map's lines) within `radius` mm; `snapped` says
 * whether it did. Ties go to the first candidate.
 */
export function snapToEndpoint(p: Pt, candidates: readonly Pt[], radius: number): { p: Pt; snapped: boolean } {
  let best: Pt | null = null;
  let bestD = radius;
  for (const c of candidates) {
    const d = Math.hypot(c.x - p.x, c.y - p.y);
    if (d <= bestD && (best === null || d < bestD)) {
      best = c;
      bestD = d;
    }
  }
  return best === null ? { p: { ...p }, snapped: false } : { p: { ...best }, snapped: true };
}

/** Endpoint snap first (it is what a map maker aims at), then the grid. */
export function snap(p: Pt, candidates: readonly Pt[], radius: number, step: number): Pt {
  const e = snapToEndpoint(p, candidates, radius);
  return e.snapped ? e.p : snapToGrid(p, step);
}
