/**
 * Path points of roadmap edges (guide 5.5: "The edges and the path points specify the path"): which edge or path
 * point is under the pointer, and the edits that insert, move and delete a path point. An edge's path runs from
 * its start station through its path points to its end station; a new point goes into the piece of that path
 * nearest to it. Pure: edits are roadmapdoc.ts `Edit`s, applied (and undone) by its RoadmapHistory.
 */
import type { Edit, RoadmapDoc } from "./roadmapdoc";

/** The path of edge `k`: start station, path points, end station (x0, y0, ... mm); null if a station is missing. */
export function edgePath(doc: RoadmapDoc, k: number): number[] | null {
  const e = doc.edges[k];
  const a = doc.stations.find((s) => s.id === e?.start);
  const b = doc.stations.find((s) => s.id === e?.end);
  return e === undefined || a === undefined || b === undefined ? null : [a.x, a.y, ...e.points, b.x, b.y];
}

function segDistance(px: number, py: number, ax: number, ay: number, bx: number, by: number): number {
  const len2 = (bx - ax) ** 2 + (by - ay) ** 2;
  const u = len2 === 0 ? 0 : Math.max(0, Math.min(1, ((px - ax) * (bx - ax) + (py - ay) * (by - ay)) / len2));
  return Math.hypot(px - (ax + u * (bx - ax)), py - (ay + u * (by - ay)));
}

/** The piece of `path` nearest (x, y): its index (0 = from the first point to the second) and distance. */
function nearestPiece(path: readonly number[], x: number, y: number): { piece: number; d: number } {
  let best = { piece: 0, d: Number.POSITIVE_INFINITY };
  for (let i = 0; i + 3 < path.length; i += 2) {
    const d = segDistance(x, y, path[i], path[i + 1], path[i + 2], path[i + 3]);
    if (d < best.d) {
      best = { piece: i / 2, d };
    }
  }
  return best;
}

/** The edge whose path passes within `tol` mm of (x, y), the nearest; null when none. */
export function edgeAt(doc: RoadmapDoc, x: number, y: number, tol: number): number | null {
  let best: number | null = null;
  let bestD = tol;
  doc.edges.forEach((_, k) => {
    const path = edgePath(doc, k);
    const d = path === null ? Number.POSITIVE_INFINITY : nearestPiece(path, x, y).d;
    if (d <= bestD) {
      bestD = d;
      best = k;
    }
  });
  return best;
}

/** The path point within `tol` mm of (x, y), the nearest: its edge and its index along the edge. */
export function pathPointAt(doc: RoadmapDoc, x: number, y: number, tol: number): { edge: number; k: number } | null {
  let best: { edge: number; k: number } | null = null;
  let bestD = tol;
  doc.edges.forEach((e, edge) => {
    for (let i = 0; i + 1 < e.points.length; i += 2) {
      const d = Math.hypot(e.points[i] - x, e.points[i + 1] - y);
      if (d <= bestD) {
        bestD = d;
        best = { edge, k: i / 2 };
      }
    }
  });
  return best;
}

const noEdge = (doc: RoadmapDoc, edge: number): string | null =>
  edgePath(doc, edge) === null ? `no edge ${edge} between two stations of the roadmap` : null;

/** Insert a path point at (x, y) into the piece of edge `edge`'s path nearest to it. */
export const insertPathPoint =
  (edge: number, x: number, y: number): Edit =>
  (doc) => {
    const bad = noEdge(doc, edge);
    if (bad !== null) {
      return bad;
    }
    const path = edgePath(doc, edge) as number[];
    const { piece } = nearestPiece(path, x, y);
    doc.edges[edge].points.splice(2 * piece, 0, x, y);
    return null;
  };

/** Move path point `k` of edge `edge` to (x, y). */
export const movePathPoint =
  (edge: number, k: number, x: number, y: number): Edit =>
  (doc) => {
    const e = doc.edges[edge];
    if (e === undefined || 2 * k + 1 >= e.points.length || k < 0) {
      return `edge ${edge} has no path point ${k}`;
    }
    e.points[2 * k] = x;
    e.points[2 * k + 1] = y;
    return null;
  };

/** Delete path point `k` of edge `edge`. */
export const deletePathPoint =
  (edge: number, k: number): Edit =>
  (doc) => {
    const e = doc.edges[edge];
    if (e === undefined || 2 * k + 1 >= e.points.length || k < 0) {
      return `edge ${edge} has no path point ${k}`;
    }
    e.points.splice(2 * k, 2);
    return null;
  };
