/**
 * What an edit changed in a scene, for the incremental redraw (issue 20): the editor's commands never change an
 * object in place (commands.ts replaces, inserts or removes whole objects), so comparing two object lists by
 * identity finds the one window that differs: a common head, a common tail, and between them the objects of the
 * base that are gone (`start`..`baseEnd`) and those of the current list that are new (`start`..`curEnd`).
 * O(n) pointer compares, no allocation.
 */

export interface ChangedWindow {
  start: number;
  /** end (exclusive) of the base's replaced objects */
  baseEnd: number;
  /** end (exclusive) of the current list's new objects */
  curEnd: number;
}

export function changedWindow(base: readonly unknown[], cur: readonly unknown[]): ChangedWindow {
  const n = Math.min(base.length, cur.length);
  let start = 0;
  while (start < n && base[start] === cur[start]) {
    start++;
  }
  let baseEnd = base.length;
  let curEnd = cur.length;
  while (baseEnd > start && curEnd > start && base[baseEnd - 1] === cur[curEnd - 1]) {
    baseEnd--;
    curEnd--;
  }
  return { start, baseEnd, curEnd };
}

/** How many objects a window touches (the base's removed plus the current's new). */
export function windowSize(w: ChangedWindow): number {
  return w.baseEnd - w.start + (w.curEnd - w.start);
}

/** Per-kind counts of the current list from the base's counts and the window (countKinds without the O(n) pass). */
export function patchCounts(
  baseCounts: Readonly<Record<string, number>>,
  base: readonly { kind: string }[],
  cur: readonly { kind: string }[],
  w: ChangedWindow,
): Record<string, number> {
  const out: Record<string, number> = { ...baseCounts };
  for (let i = w.start; i < w.baseEnd; i++) {
    out[base[i].kind] = (out[base[i].kind] ?? 0) - 1;
  }
  for (let i = w.start; i < w.curEnd; i++) {
    out[cur[i].kind] = (out[cur[i].kind] ?? 0) + 1;
  }
  return out;
}

export interface Box {
  minX: number;
  minY: number;
  maxX: number;
  maxY: number;
}

type Shape = { points: readonly number[]; r?: number };

function grow(b: Box | null, o: Shape): Box | null {
  const r = o.r ?? 0;
  for (let i = 0; i + 1 < o.points.length; i += 2) {
    const x = o.points[i];
    const y = o.points[i + 1];
    b ??= { minX: x - r, minY: y - r, maxX: x + r, maxY: y + r };
    b = { minX: Math.min(b.minX, x - r), minY: Math.min(b.minY, y - r), maxX: Math.max(b.maxX, x + r), maxY: Math.max(b.maxY, y + r) };
  }
  return b;
}

/** The world box of every object a window touches (the base's gone ones and the current's new ones); null: none. */
export function windowBox(base: readonly Shape[], cur: readonly Shape[], w: ChangedWindow): Box | null {
  let b: Box | null = null;
  for (let i = w.start; i < w.baseEnd; i++) {
    b = grow(b, base[i]);
  }
  for (let i = w.start; i < w.curEnd; i++) {
    b = grow(b, cur[i]);
  }
  return b;
}

export function union(a: Box | null, b: Box | null): Box | null {
  if (a === null || b === null) {
    return a ?? b;
  }
  return { minX: Math.min(a.minX, b.minX), minY: Math.min(a.minY, b.minY), maxX: Math.max(a.maxX, b.maxX), maxY: Math.max(a.maxY, b.maxY) };
}

interface Cam {
  cx: number;
  cy: number;
  scale: number;
  width: number;
  height: number;
}

/**
 * The part of a layer to redraw for a world box (dirty region): whole CSS pixels `x`, `y`, `width`, `height` of the
 * layer, the box widened by `pad` px (ticks, strokes) and cut to the layer; and a camera for that part alone (the
 * same scale, so a point lands at its layer position minus (x, y)). Null when the box misses the layer.
 */
export function dirtyPart(cam: Cam, box: Box, pad: number): { x: number; y: number; cam: Cam } | null {
  const x0 = Math.max(0, Math.floor((box.minX - cam.cx) * cam.scale + cam.width / 2 - pad));
  const y0 = Math.max(0, Math.floor((cam.cy - box.maxY) * cam.scale + cam.height / 2 - pad));
  const x1 = Math.min(Math.ceil(cam.width), Math.ceil((box.maxX - cam.cx) * cam.scale + cam.width / 2 + pad));
  const y1 = Math.min(Math.ceil(cam.height), Math.ceil((cam.cy - box.minY) * cam.scale + cam.height / 2 + pad));
  if (x1 <= x0 || y1 <= y0) {
    return null;
  }
  const width = x1 - x0;
  const height = y1 - y0;
  return {
    x: x0,
    y: y0,
    cam: {
      scale: cam.scale,
      width,
      height,
      cx: cam.cx + (x0 + width / 2 - cam.width / 2) / cam.scale,
      cy: cam.cy - (y0 + height / 2 - cam.height / 2) / cam.scale,
    },
  };
}
