/**
 * Convert lines from the laser scan (guide 5.4 "Convert line from scan"): split-and-merge over the scan's points
 * in scan order, a total-least-squares fit per piece, then the length rules of the Mapping parameters
 * (guide 5.9: MinLineLenAux "Minimum length of auxiliary lines [mm]: lines extracted from scan", MinLineLenMap
 * "Minimum length of mapped lines [mm]"). Erratum E-GUI-004: a fitted line at least MinLineLenMap long becomes a
 * <linemapped>, one at least MinLineLenAux long an <auxlinemapped>, a shorter one is dropped.
 *
 * Each line is turned so that its front (the left side, E-GUI-002) faces the scanner. Pure: points in, lines out.
 */
import { clean, type Pt, type Seg } from "./geometry";

export interface FitOptions {
  /** The scanner's position (mm): every line's front faces it. */
  origin: Pt;
  minLineLenAux: number;
  minLineLenMap: number;
  /** A point farther than this (mm) from a piece's line splits the piece. */
  threshold?: number;
  /** Consecutive points farther apart than this (mm) start a new cluster. */
  maxGap?: number;
  /** Fewer points than this make no line. */
  minPoints?: number;
}

export interface FittedLine extends Seg {
  kind: "linemapped" | "auxlinemapped";
  /** How many scan points support it. */
  support: number;
}

interface Fit {
  cx: number;
  cy: number;
  ux: number;
  uy: number;
  /** The largest distance of a point to the fitted line. */
  worst: number;
}

/** Total least squares over pts[i..j] (inclusive): the centroid and the principal direction. */
function fitRange(pts: readonly Pt[], i: number, j: number): Fit {
  const n = j - i + 1;
  let cx = 0;
  let cy = 0;
  for (let k = i; k <= j; k++) {
    cx += pts[k].x;
    cy += pts[k].y;
  }
  cx /= n;
  cy /= n;
  let sxx = 0;
  let syy = 0;
  let sxy = 0;
  for (let k = i; k <= j; k++) {
    const dx = pts[k].x - cx;
    const dy = pts[k].y - cy;
    sxx += dx * dx;
    syy += dy * dy;
    sxy += dx * dy;
  }
  const theta = 0.5 * Math.atan2(2 * sxy, sxx - syy);
  const ux = Math.cos(theta);
  const uy = Math.sin(theta);
  let worst = 0;
  for (let k = i; k <= j; k++) {
    worst = Math.max(worst, Math.abs(-(pts[k].x - cx) * uy + (pts[k].y - cy) * ux));
  }
  return { cx, cy, ux, uy, worst };
}

/** The point of pts[i+1..j-1] farthest from the chord pts[i] -> pts[j], and that distance. */
function farthest(pts: readonly Pt[], i: number, j: number): [number, number] {
  const ax = pts[i].x;
  const ay = pts[i].y;
  const dx = pts[j].x - ax;
  const dy = pts[j].y - ay;
  const len = Math.hypot(dx, dy);
  let best = -1;
  let bestD = 0;
  for (let k = i + 1; k < j; k++) {
    const px = pts[k].x - ax;
    const py = pts[k].y - ay;
    const d = len === 0 ? Math.hypot(px, py) : Math.abs(px * dy - py * dx) / len;
    if (d > bestD) {
      bestD = d;
      best = k;
    }
  }
  return [best, bestD];
}

/** Split pts[i..j] until every piece is within `threshold` of its chord; pieces as [start, end] index pairs. */
function split(pts: readonly Pt[], i: number, j: number, threshold: number): Array<[number, number]> {
  const out: Array<[number, number]> = [];
  const stack: Array<[number, number]> = [[i, j]];
  while (stack.length > 0) {
    const [s, e] = stack.pop() as [number, number];
    const [k, d] = farthest(pts, s, e);
    if (k > 0 && d > threshold) {
      stack.push([k, e], [s, k]);
    } else {
      out.push([s, e]);
    }
  }
  return out;
}

/** Merge neighbouring pieces whose joint fit stays within `threshold`. */
function merge(pts: readonly Pt[], pieces: Array<[number, number]>, threshold: number): Array<[number, number]> {
  const out: Array<[number, number]> = [];
  for (const p of pieces) {
    const last = out[out.length - 1];
    if (last !== undefined && last[1] >= p[0] - 1 && fitRange(pts, last[0], p[1]).worst <= threshold) {
      last[1] = p[1];
    } else {
      out.push([p[0], p[1]]);
    }
  }
  return out;
}

/** The segment of a fit between the projections of its first and last points, front towards `origin`. */
function segment(pts: readonly Pt[], i: number, j: number, f: Fit, origin: Pt): Seg {
  const proj = (p: Pt): Pt => {
    const t = (p.x - f.cx) * f.ux + (p.y - f.cy) * f.uy;
    return { x: clean(f.cx + t * f.ux), y: clean(f.cy + t * f.uy) };
  };
  const a = proj(pts[i]);
  const b = proj(pts[j]);
  const side = (b.x - a.x) * (origin.y - a.y) - (b.y - a.y) * (origin.x - a.x);
  return side >= 0 ? { a, b } : { a: b, b: a };
}

/** Fit lines to scan points given in scan order (the order of the laser's beams). */
export function fitScan(points: readonly Pt[], opts: FitOptions): FittedLine[] {
  const threshold = opts.threshold ?? 30;
  const maxGap = opts.maxGap ?? 300;
  const minPoints = Math.max(2, opts.minPoints ?? 5);
  const pts = points.filter((p) => Number.isFinite(p.x) && Number.isFinite(p.y));
  const out: FittedLine[] = [];
  let start = 0;
  for (let k = 1; k <= pts.length; k++) {
    const gap = k === pts.length || Math.hypot(pts[k].x - pts[k - 1].x, pts[k].y - pts[k - 1].y) > maxGap;
    if (!gap) {
      continue;
    }
    if (k - start >= minPoints) {
      const pieces = merge(pts, split(pts, start, k - 1, threshold), threshold);
      for (const [i, j] of pieces) {
        if (j - i + 1 < minPoints) {
          continue;
        }
        const seg = segment(pts, i, j, fitRange(pts, i, j), opts.origin);
        const len = Math.hypot(seg.b.x - seg.a.x, seg.b.y - seg.a.y);
        const kind = len >= opts.minLineLenMap ? "linemapped" : len >= opts.minLineLenAux ? "auxlinemapped" : null;
        if (kind !== null) {
          out.push({ ...seg, kind, support: j - i + 1 });
        }
      }
    }
    start = k;
  }
  return out;
}
