/**
 * A spatial index of the editor's objects (issue 20): which objects may lie within a distance of a point, without
 * a pass over the whole document. The hit tests (select, trim, extend, parallel, orthogonal, vertices) and the
 * endpoint snap ask it for the objects near the pointer and then run their own exact test on those alone, so the
 * answer is the linear scan's (shapes.test.ts, objindex.test.ts).
 *
 * A uniform grid of CELL mm squares keyed by cell; each object sits in the cells its box (grown by |r|, a
 * circle's radius) meets. Objects that span more than BIG_CELLS cells, or whose box is not finite, are kept aside
 * and are candidates of every query. The History (commands.ts) keeps the index in step with each change.
 */
import type { MapObject } from "../scene/map";

const CELL = 2000;
const BIG_CELLS = 256;
/** a query over more cells than this is answered by "every object" (null) */
const QUERY_CELLS = 4096;
const SPAN = 1 << 21;

interface CellBox {
  c0: number;
  r0: number;
  c1: number;
  r1: number;
}

function cellBox(o: MapObject): CellBox | null {
  const p = o.points;
  if (p.length < 2) {
    return null;
  }
  const r = Math.abs(o.r ?? 0);
  let minX = p[0],
    maxX = p[0],
    minY = p[1],
    maxY = p[1];
  for (let i = 2; i + 1 < p.length; i += 2) {
    minX = Math.min(minX, p[i]);
    maxX = Math.max(maxX, p[i]);
    minY = Math.min(minY, p[i + 1]);
    maxY = Math.max(maxY, p[i + 1]);
  }
  const b = {
    c0: Math.floor((minX - r) / CELL),
    r0: Math.floor((minY - r) / CELL),
    c1: Math.floor((maxX + r) / CELL),
    r1: Math.floor((maxY + r) / CELL),
  };
  const inRange = [b.c0, b.r0, b.c1, b.r1].every((v) => Number.isFinite(v) && Math.abs(v) < SPAN);
  return inRange ? b : null;
}

const key = (c: number, r: number): number => (c + SPAN) * 2 * SPAN + (r + SPAN);

export class ObjectIndex {
  private readonly cells = new Map<number, MapObject[]>();
  /** objects in no cell: too large, not finite (candidates of every query) */
  private readonly big = new Set<MapObject>();
  /** objects without points: never near anything */
  private readonly none = new Set<MapObject>();
  /** false once a removal did not find its object: the owner rebuilds the index */
  ok = true;

  constructor(objects: readonly MapObject[]) {
    for (const o of objects) {
      this.add(o);
    }
  }

  private each(o: MapObject, fn: (k: number) => void): "cells" | "big" | "none" {
    if (o.points.length < 2) {
      return "none";
    }
    const b = cellBox(o);
    if (b === null || (b.c1 - b.c0 + 1) * (b.r1 - b.r0 + 1) > BIG_CELLS) {
      return "big";
    }
    for (let r = b.r0; r <= b.r1; r++) {
      for (let c = b.c0; c <= b.c1; c++) {
        fn(key(c, r));
      }
    }
    return "cells";
  }

  add(o: MapObject): void {
    const where = this.each(o, (k) => {
      const list = this.cells.get(k);
      if (list === undefined) {
        this.cells.set(k, [o]);
      } else {
        list.push(o);
      }
    });
    if (where !== "cells") {
      (where === "big" ? this.big : this.none).add(o);
    }
  }

  remove(o: MapObject): void {
    const where = this.each(o, (k) => {
      const list = this.cells.get(k);
      const at = list === undefined ? -1 : list.indexOf(o);
      if (list === undefined || at < 0) {
        this.ok = false;
        return;
      }
      list[at] = list[list.length - 1];
      list.pop();
      if (list.length === 0) {
        this.cells.delete(k);
      }
    });
    if (where !== "cells" && !(where === "big" ? this.big : this.none).delete(o)) {
      this.ok = false;
    }
  }

  /**
   * The objects whose box grown by `tol` contains (x, y), each once, in no particular order (a superset of those
   * with a point or an outline within `tol`); null when the query covers too many cells to be worth it.
   */
  near(x: number, y: number, tol: number): MapObject[] | null {
    const c0 = Math.floor((x - tol) / CELL),
      c1 = Math.floor((x + tol) / CELL);
    const r0 = Math.floor((y - tol) / CELL),
      r1 = Math.floor((y + tol) / CELL);
    if (
      !((c1 - c0 + 1) * (r1 - r0 + 1) <= QUERY_CELLS) ||
      !(Math.abs(c0) < SPAN && Math.abs(c1) < SPAN && Math.abs(r0) < SPAN && Math.abs(r1) < SPAN)
    ) {
      return null;
    }
    const out = new Set<MapObject>(this.big);
    for (let r = r0; r <= r1; r++) {
      for (let c = c0; c <= c1; c++) {
        for (const o of this.cells.get(key(c, r)) ?? []) {
          out.add(o);
        }
      }
    }
    return [...out];
  }
}

/**
 * `candidates` (objects of `objects`) in document order; objects no longer in the document are dropped, and
 * `stale` says whether there were any.
 */
export function inDocumentOrder(
  objects: readonly MapObject[],
  candidates: readonly MapObject[],
): { list: MapObject[]; stale: boolean } {
  if (candidates.length <= 16) {
    const at = candidates.map((o) => ({ o, k: objects.indexOf(o) }));
    const list = at
      .filter((e) => e.k >= 0)
      .sort((a, b) => a.k - b.k)
      .map((e) => e.o);
    return { list, stale: list.length !== candidates.length };
  }
  const want = new Set(candidates);
  const list = objects.filter((o) => want.has(o));
  return { list, stale: list.length !== want.size };
}
