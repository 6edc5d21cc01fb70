import { describe, expect, it } from "vitest";
import type { Pt } from "../src/editor/geometry";
import { fitScan } from "../src/editor/scanfit";

function run(x0: number, y0: number, x1: number, y1: number, step: number): Pt[] {
  const n = Math.round(Math.hypot(x1 - x0, y1 - y0) / step);
  return Array.from({ length: n + 1 }, (_, i) => ({ x: x0 + ((x1 - x0) * i) / n, y: y0 + ((y1 - y0) * i) / n }));
}

const params = { origin: { x: 0, y: 0 }, minLineLenAux: 200, minLineLenMap: 500 };

describe("fitScan", () => {
  // In scan order (counter-clockwise from the right): the right wall, the corner, the top wall; then, after a
  // gap, a 300 mm piece (auxiliary) and a 150 mm piece (below MinLineLenAux: dropped).
  const corner = [...run(2000, -1000, 2000, 2000, 50), ...run(2000, 2000, -1000, 2000, 50).slice(1)];
  const aux = run(-1500, 1300, -1500, 1000, 50);
  const tiny = run(-1500, 400, -1500, 250, 25);

  it("fits exact lines, fronts towards the scanner, kinds by MinLineLenMap and MinLineLenAux", () => {
    expect(fitScan([...corner, ...aux, ...tiny], params)).toEqual([
      { a: { x: 2000, y: -1000 }, b: { x: 2000, y: 2000 }, kind: "linemapped", support: 61 },
      { a: { x: 2000, y: 2000 }, b: { x: -1000, y: 2000 }, kind: "linemapped", support: 61 },
      { a: { x: -1500, y: 1300 }, b: { x: -1500, y: 1000 }, kind: "auxlinemapped", support: 7 },
    ]);
  });
  it("honours the parameters: a larger MinLineLenAux drops the short line", () => {
    const out = fitScan([...corner, ...aux], { ...params, minLineLenAux: 400 });
    expect(out.map((l) => l.kind)).toEqual(["linemapped", "linemapped"]);
    const all = fitScan([...corner, ...aux], { ...params, minLineLenMap: 200 });
    expect(all.map((l) => l.kind)).toEqual(["linemapped", "linemapped", "linemapped"]);
  });
  it("stays within 30 mm of the wall with noisy points, and ignores junk", () => {
    let seed = 7;
    const rnd = (): number => {
      seed = (seed * 1103515245 + 12345) % 2147483648;
      return seed / 2147483648 - 0.5;
    };
    const noisy = run(3000, -2000, 3000, 2000, 40).map((p) => ({ x: p.x + 20 * rnd(), y: p.y }));
    const out = fitScan([...noisy, { x: Number.NaN, y: 0 }], params);
    expect(out.length).toBe(1);
    for (const p of [out[0].a, out[0].b]) {
      expect(Math.abs(p.x - 3000)).toBeLessThan(30);
    }
    expect(out[0].a.y).toBeLessThan(out[0].b.y); // front (left of a -> b) faces the scanner at the origin
  });
  it("turns a line so its front faces the scanner whatever the order of the points", () => {
    const cw = run(2000, 2000, 2000, -1000, 50);
    expect(fitScan(cw, params)).toEqual([
      { a: { x: 2000, y: -1000 }, b: { x: 2000, y: 2000 }, kind: "linemapped", support: 61 },
    ]);
    expect(fitScan(cw, { ...params, origin: { x: 5000, y: 0 } })).toEqual([
      { a: { x: 2000, y: 2000 }, b: { x: 2000, y: -1000 }, kind: "linemapped", support: 61 },
    ]);
  });
  it("makes nothing of too few points", () => {
    expect(fitScan([], params)).toEqual([]);
    expect(fitScan(run(0, 1000, 1000, 1000, 500), params)).toEqual([]);
  });
});
