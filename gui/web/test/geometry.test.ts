import { describe, expect, it } from "vitest";
import {
  extend,
  frontNormal,
  invert,
  orthogonal,
  parallel,
  type Seg,
  snap,
  snapToEndpoint,
  snapToGrid,
  trim,
} from "../src/editor/geometry";

const seg = (x0: number, y0: number, x1: number, y1: number): Seg => ({ a: { x: x0, y: y0 }, b: { x: x1, y: y1 } });
const dot: Seg = seg(1, 1, 1, 1);

describe("trim", () => {
  const s = seg(0, 0, 10, 0);
  const r = seg(4, -2, 4, 3);
  it("keeps the longer piece without a click", () => {
    expect(trim(s, r)).toEqual({ ok: true, value: seg(4, 0, 10, 0) });
  });
  it("keeps the piece on the clicked side", () => {
    expect(trim(s, r, { x: 1, y: 0 })).toEqual({ ok: true, value: seg(0, 0, 4, 0) });
    expect(trim(s, r, { x: 9, y: 0.5 })).toEqual({ ok: true, value: seg(4, 0, 10, 0) });
  });
  it("trims a slanted line at the exact crossing", () => {
    expect(trim(seg(0, 0, 3000, 4000), seg(0, 2000, 3000, 2000), { x: 0, y: 0 })).toEqual({
      ok: true,
      value: seg(0, 0, 1500, 2000),
    });
  });
  it("refuses a parallel reference, saying why", () => {
    expect(trim(s, seg(0, 5, 10, 5))).toEqual({ ok: false, reason: "the lines are parallel: they never cross" });
  });
  it("refuses a reference that crosses outside the line", () => {
    const r2 = trim(s, seg(12, -1, 12, 1));
    expect(r2.ok).toBe(false);
    expect(!r2.ok && r2.reason).toMatch(/nothing to trim/);
  });
  it("refuses when only the reference's extension crosses", () => {
    const r2 = trim(s, seg(4, 1, 4, 3));
    expect(!r2.ok && r2.reason).toMatch(/extension/);
  });
  it("refuses a zero-length line or reference", () => {
    expect(trim(dot, r)).toEqual({ ok: false, reason: "the line has zero length" });
    expect(trim(s, dot)).toEqual({ ok: false, reason: "the reference line has zero length" });
  });
});

describe("extend", () => {
  it("moves the end nearer the reference onto it", () => {
    expect(extend(seg(0, 0, 3, 0), seg(5, -1, 5, 1))).toEqual({ ok: true, value: seg(0, 0, 5, 0) });
    expect(extend(seg(2, 0, 4, 0), seg(-1, -1, -1, 1))).toEqual({ ok: true, value: seg(-1, 0, 4, 0) });
    expect(extend(seg(0, 0, 300, 400), seg(0, 2000, 3000, 2000))).toEqual({ ok: true, value: seg(0, 0, 1500, 2000) });
  });
  it("refuses a line that never meets the reference", () => {
    const r = extend(seg(0, 0, 3, 0), seg(5, 1, 5, 3));
    expect(!r.ok && r.reason).toMatch(/never meets/);
    expect(extend(seg(0, 0, 3, 0), seg(0, 1, 3, 1))).toEqual({
      ok: false,
      reason: "the lines are parallel: the line never reaches the reference line",
    });
  });
  it("refuses a line that already reaches the reference", () => {
    const r = extend(seg(0, 0, 3, 0), seg(2, -1, 2, 1));
    expect(!r.ok && r.reason).toMatch(/already reaches/);
  });
  it("refuses a zero-length line", () => {
    expect(extend(dot, seg(5, -1, 5, 1))).toEqual({ ok: false, reason: "the line has zero length" });
  });
});

describe("parallel and orthogonal", () => {
  const s = seg(1, 1, 4, 5); // length 5
  const x = seg(0, 0, 10, 0);
  it("turns about the chosen end and keeps the length", () => {
    expect(parallel(s, x, "a")).toEqual({ ok: true, value: seg(1, 1, 6, 1) });
    expect(parallel(s, x, "b")).toEqual({ ok: true, value: seg(-1, 5, 4, 5) });
    expect(orthogonal(s, x, "a")).toEqual({ ok: true, value: seg(1, 1, 1, 6) });
    expect(orthogonal(s, x, "b")).toEqual({ ok: true, value: seg(4, 0, 4, 5) });
  });
  it("keeps the line's own sense (the nearer of the two directions)", () => {
    const diag = seg(0, 0, 3, 4);
    expect(parallel(seg(0, 0, 10, 0), diag)).toEqual({ ok: true, value: seg(0, 0, 6, 8) });
    expect(parallel(seg(0, 0, -10, 0), diag)).toEqual({ ok: true, value: seg(0, 0, -6, -8) });
    expect(orthogonal(seg(0, 0, 10, 0), diag)).toEqual({ ok: true, value: seg(0, 0, 8, -6) });
  });
  it("refuses zero-length lines", () => {
    expect(parallel(dot, x)).toEqual({ ok: false, reason: "the line has zero length" });
    expect(orthogonal(s, dot)).toEqual({ ok: false, reason: "the reference line has zero length" });
  });
});

describe("invert", () => {
  it("swaps the ends, so the front (left) turns to the other side", () => {
    expect(invert(seg(0, 0, 10, 0))).toEqual({ ok: true, value: seg(10, 0, 0, 0) });
    expect(frontNormal(seg(0, 0, 10, 0))).toEqual({ ok: true, value: { x: 0, y: 1 } });
    expect(frontNormal(seg(10, 0, 0, 0))).toEqual({ ok: true, value: { x: 0, y: -1 } });
    expect(invert(dot)).toEqual({ ok: false, reason: "the line has zero length" });
  });
});

describe("snapping", () => {
  it("snaps to the grid", () => {
    expect(snapToGrid({ x: 123, y: -76 }, 50)).toEqual({ x: 100, y: -100 });
    expect(snapToGrid({ x: 125, y: 24.9 }, 50)).toEqual({ x: 150, y: 0 });
    expect(snapToGrid({ x: 0.31, y: 0.29 }, 0.1)).toEqual({ x: 0.3, y: 0.3 });
    expect(snapToGrid({ x: 7, y: 8 }, 0)).toEqual({ x: 7, y: 8 });
  });
  it("snaps to the nearest endpoint within the radius", () => {
    const ends = [
      { x: 1000, y: 1000 },
      { x: 1030, y: 1000 },
    ];
    expect(snapToEndpoint({ x: 1020, y: 1005 }, ends, 50)).toEqual({ p: { x: 1030, y: 1000 }, snapped: true });
    expect(snapToEndpoint({ x: 1200, y: 1000 }, ends, 50)).toEqual({ p: { x: 1200, y: 1000 }, snapped: false });
  });
  it("prefers an endpoint to the grid", () => {
    expect(snap({ x: 1020, y: 1005 }, [{ x: 1013, y: 997 }], 50, 100)).toEqual({ x: 1013, y: 997 });
    expect(snap({ x: 1260, y: 1005 }, [{ x: 1013, y: 997 }], 50, 100)).toEqual({ x: 1300, y: 1000 });
  });
});
