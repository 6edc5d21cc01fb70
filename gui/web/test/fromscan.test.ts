import { describe, expect, it } from "vitest";
import { linesFromScan, scanToWorld } from "../src/editor/fromscan";

describe("convert lines from the scan", () => {
  it("puts the scan into the map's frame with the estimated pose (angle in 1/1000 degree)", () => {
    const pts = scanToWorld({
      estX: 1000,
      estY: 2000,
      estAngle: 90000,
      scan: [
        { x: 500, y: 0 },
        { x: 0, y: 300 },
      ],
    });
    expect(pts.map((p) => [Math.round(p.x * 1e6) / 1e6, Math.round(p.y * 1e6) / 1e6])).toEqual([
      [1000, 2500],
      [700, 2000],
    ]);
  });
  it("fits a wall seen from a turned platform at its place in the map, front towards the platform", () => {
    // a wall along y = 3000 from x 0 to 4000, seen from (2000, 1000) facing 30 degrees
    const a = (30 * Math.PI) / 180;
    const scan = [];
    for (let x = 0; x <= 4000; x += 50) {
      const [dx, dy] = [x - 2000, 2000];
      scan.push({ x: dx * Math.cos(a) + dy * Math.sin(a), y: -dx * Math.sin(a) + dy * Math.cos(a) });
    }
    const objs = linesFromScan(
      { estX: 2000, estY: 1000, estAngle: 30000, scan },
      { MinLineLenAux: 200, MinLineLenMap: 500 },
    );
    expect(objs).toEqual([{ kind: "linemapped", layer: 0, points: [4000, 3000, 0, 3000], attrs: {} }]);
  });
  it("drops lines shorter than MinLineLenAux", () => {
    const scan = Array.from({ length: 10 }, (_, k) => ({ x: 1000, y: k * 10 }));
    expect(linesFromScan({ estX: 0, estY: 0, estAngle: 0, scan }, { MinLineLenAux: 200, MinLineLenMap: 500 })).toEqual(
      [],
    );
  });
});
