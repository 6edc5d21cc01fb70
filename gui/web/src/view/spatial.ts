/**
 * A uniform grid over segments: which segments may lie in a rectangle (viewport culling). Built once per map;
 * a query visits the cells the rectangle covers and returns each segment once (a stamp per query, no Set).
 */
import type { Bounds } from "../scene/map";

export class SegmentGrid {
  readonly n: number;
  private readonly cellStart: Uint32Array;
  private readonly items: Uint32Array;
  private readonly stamps: Uint32Array;
  private stamp = 0;
  private readonly minX: number;
  private readonly minY: number;
  private readonly cell: number;
  readonly cols: number;
  readonly rows: number;

  /** `segs`: x1, y1, x2, y2 per segment. */
  constructor(
    readonly segs: Float64Array,
    bounds: Bounds,
    targetPerCell = 8,
  ) {
    this.n = segs.length / 4;
    const w = Math.max(bounds.maxX - bounds.minX, 1);
    const h = Math.max(bounds.maxY - bounds.minY, 1);
    const cells = Math.max(1, Math.min(1 << 18, Math.ceil(this.n / targetPerCell)));
    this.cell = Math.max(Math.sqrt((w * h) / cells), 1);
    this.cols = Math.max(1, Math.ceil(w / this.cell));
    this.rows = Math.max(1, Math.ceil(h / this.cell));
    this.minX = bounds.minX;
    this.minY = bounds.minY;
    const counts = new Uint32Array(this.cols * this.rows + 1);
    this.forCells(segs, (c) => counts[c + 1]++);
    for (let i = 1; i < counts.length; i++) {
      counts[i] += counts[i - 1];
    }
    this.cellStart = counts;
    this.items = new Uint32Array(counts[counts.length - 1]);
    const fill = counts.slice(0, -1);
    this.forCells(segs, (c, s) => (this.items[fill[c]++] = s));
    this.stamps = new Uint32Array(this.n);
  }

  private clampCol(x: number): number {
    return Math.min(this.cols - 1, Math.max(0, Math.floor((x - this.minX) / this.cell)));
  }

  private clampRow(y: number): number {
    return Math.min(this.rows - 1, Math.max(0, Math.floor((y - this.minY) / this.cell)));
  }

  private forCells(segs: Float64Array, fn: (cell: number, seg: number) => void): void {
    for (let s = 0; s < this.n; s++) {
      const x1 = segs[4 * s],
        y1 = segs[4 * s + 1],
        x2 = segs[4 * s + 2],
        y2 = segs[4 * s + 3];
      const c0 = this.clampCol(Math.min(x1, x2)),
        c1 = this.clampCol(Math.max(x1, x2));
      const r0 = this.clampRow(Math.min(y1, y2)),
        r1 = this.clampRow(Math.max(y1, y2));
      for (let r = r0; r <= r1; r++) {
        for (let c = c0; c <= c1; c++) {
          fn(r * this.cols + c, s);
        }
      }
    }
  }

  /** Indices of the segments whose bounding box may meet `b` (each once), into `out`; returns the count. */
  query(b: Bounds, out: Uint32Array): number {
    this.stamp = (this.stamp + 1) >>> 0;
    if (this.stamp === 0) {
      this.stamps.fill(0);
      this.stamp = 1;
    }
    const c0 = this.clampCol(b.minX),
      c1 = this.clampCol(b.maxX);
    const r0 = this.clampRow(b.minY),
      r1 = this.clampRow(b.maxY);
    let k = 0;
    const segs = this.segs;
    for (let r = r0; r <= r1; r++) {
      for (let c = c0; c <= c1; c++) {
        const cell = r * this.cols + c;
        for (let i = this.cellStart[cell]; i < this.cellStart[cell + 1]; i++) {
          const s = this.items[i];
          if (this.stamps[s] === this.stamp) {
            continue;
          }
          this.stamps[s] = this.stamp;
          const x1 = segs[4 * s],
            y1 = segs[4 * s + 1],
            x2 = segs[4 * s + 2],
            y2 = segs[4 * s + 3];
          if (
            Math.max(x1, x2) < b.minX ||
            Math.min(x1, x2) > b.maxX ||
            Math.max(y1, y2) < b.minY ||
            Math.min(y1, y2) > b.maxY
          ) {
            continue;
          }
          out[k++] = s;
        }
      }
    }
    return k;
  }
}
