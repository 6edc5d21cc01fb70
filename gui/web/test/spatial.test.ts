import { describe, expect, it } from "vitest";
import { SegmentGrid } from "../src/view/spatial";
import { gridStep } from "../src/view/maprender";

function brute(segs: Float64Array, b: { minX: number; minY: number; maxX: number; maxY: number }): number[] {
  const out: number[] = [];
  for (let s = 0; s < segs.length / 4; s++) {
    const [x1, y1, x2, y2] = segs.subarray(4 * s, 4 * s + 4);
    if (
      Math.max(x1, x2) >= b.minX &&
      Math.min(x1, x2) <= b.maxX &&
      Math.max(y1, y2) >= b.minY &&
      Math.min(y1, y2) <= b.maxY
    ) {
      out.push(s);
    }
  }
  return out;
}

describe("SegmentGrid", () => {
  it("returns exactly the segments whose box meets the query, each once", () => {
    let seed = 7;
    const rnd = () => (seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648;
    const n = 5000;
    const segs = new Float64Array(4 * n);
    for (let i = 0; i < n; i++) {
      const x = rnd() * 100000,
        y = rnd() * 50000,
        long = rnd() < 0.05 ? 40000 : 2000;
      segs.set([x, y, x + (rnd() - 0.5) * long, y + (rnd() - 0.5) * long], 4 * i);
    }
    const grid = new SegmentGrid(segs, { minX: -20000, minY: -20000, maxX: 120000, maxY: 70000 });
    const out = new Uint32Array(n);
    for (let q = 0; q < 50; q++) {
      const x = rnd() * 100000,
        y = rnd() * 50000,
        w = rnd() * 30000,
        h = rnd() * 20000;
      const b = { minX: x, minY: y, maxX: x + w, maxY: y + h };
      const k = grid.query(b, out);
      expect(Array.from(out.subarray(0, k)).sort((a, c) => a - c)).toEqual(brute(segs, b));
    }
  });
  it("handles a query outside the grid", () => {
    const segs = new Float64Array([0, 0, 10, 10]);
    const grid = new SegmentGrid(segs, { minX: 0, minY: 0, maxX: 10, maxY: 10 });
    expect(grid.query({ minX: 100, minY: 100, maxX: 200, maxY: 200 }, new Uint32Array(1))).toBe(0);
  });
});

describe("gridStep", () => {
  it("keeps grid lines 40 to 200 px apart on round steps", () => {
    for (const scale of [0.0001, 0.001, 0.01, 0.05, 0.3, 1]) {
      const step = gridStep(scale);
      expect(step * scale).toBeGreaterThanOrEqual(40);
      expect(String(step)).toMatch(/^[125]0*$/);
    }
  });
});
