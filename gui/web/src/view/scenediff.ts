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
    b = {
      minX: Math.min(b.minX, x - r),
      minY: Math.min(b.minY, y - r),
      maxX: Math.max(b.maxX, x + r),
      maxY: Math.max(b.maxY, y + r),
    };
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
  return {
    minX: Math.min(a.minX, b.minX),
    minY: Math.min(a.minY, b.minY),
    maxX: Math.max(a.maxX, b.maxX),
    maxY: Math.max(a.maxY, b.maxY),
  };
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

/**
 * The boxes of every head and every tail of an object list (prefix and suffix unions, as sceneBounds computes a
 * box: each point grown by the object's r), so that the box of the list outside one window is two look-ups: the
 * bounds of a scene after an edit, exact, without a pass over its 50,000 objects (issue 20).
 */
export class HeadTailBoxes {
  /** head[k]: the box of objects [0, k); tail[k]: of objects [k, n); as minX, minY, maxX, maxY at 4k */
  private readonly head: Float64Array;
  private readonly tail: Float64Array;
  /** whether head[k] / tail[k] holds any point (a box alone cannot say: a negative r turns it inside out) */
  private readonly headAny: Uint8Array;
  private readonly tailAny: Uint8Array;

  constructor(objects: readonly Shape[]) {
    const n = objects.length;
    this.head = new Float64Array(4 * (n + 1));
    this.tail = new Float64Array(4 * (n + 1));
    this.headAny = new Uint8Array(n + 1);
    this.tailAny = new Uint8Array(n + 1);
    const box = (a: Float64Array, k: number, from: number, o: Shape): void => {
      let [x0, y0, x1, y1] = [a[4 * from], a[4 * from + 1], a[4 * from + 2], a[4 * from + 3]];
      const r = o.r ?? 0;
      for (let i = 0; i + 1 < o.points.length; i += 2) {
        x0 = Math.min(x0, o.points[i] - r);
        y0 = Math.min(y0, o.points[i + 1] - r);
        x1 = Math.max(x1, o.points[i] + r);
        y1 = Math.max(y1, o.points[i + 1] + r);
      }
      a.set([x0, y0, x1, y1], 4 * k);
    };
    const empty = [Infinity, Infinity, -Infinity, -Infinity];
    this.head.set(empty, 0);
    this.tail.set(empty, 4 * n);
    for (let k = 0; k < n; k++) {
      box(this.head, k + 1, k, objects[k]);
      this.headAny[k + 1] = this.headAny[k] | (objects[k].points.length >= 2 ? 1 : 0);
    }
    for (let k = n - 1; k >= 0; k--) {
      box(this.tail, k, k + 1, objects[k]);
      this.tailAny[k] = this.tailAny[k + 1] | (objects[k].points.length >= 2 ? 1 : 0);
    }
  }

  /** The box of the objects before `start` and from `end` on; null when they have no point. */
  outside(start: number, end: number): Box | null {
    const part = (a: Float64Array, k: number): Box => ({
      minX: a[4 * k],
      minY: a[4 * k + 1],
      maxX: a[4 * k + 2],
      maxY: a[4 * k + 3],
    });
    return union(this.headAny[start] ? part(this.head, start) : null, this.tailAny[end] ? part(this.tail, end) : null);
  }
}
