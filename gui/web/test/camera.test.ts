import { describe, expect, it } from "vitest";
import { fit, panBy, toScreen, toWorld, viewBounds, zoomAt } from "../src/view/camera";

const cam = { cx: 1000, cy: 2000, scale: 0.1, width: 800, height: 600 };

describe("camera", () => {
  it("maps the centre to the canvas centre and y up to screen up", () => {
    expect(toScreen(cam, 1000, 2000)).toEqual([400, 300]);
    expect(toScreen(cam, 2000, 3000)).toEqual([500, 200]);
    expect(toWorld(cam, 500, 200)).toEqual([2000, 3000]);
  });
  it("pans by screen pixels", () => {
    const c = panBy(cam, 100, -50);
    expect(c.cx).toBe(0);
    expect(c.cy).toBe(1500);
  });
  it("zooms about the pointer: the world point under it stays", () => {
    const before = toWorld(cam, 123, 456);
    const c = zoomAt(cam, 2, 123, 456);
    expect(c.scale).toBe(0.2);
    const after = toWorld(c, 123, 456);
    expect(after[0]).toBeCloseTo(before[0], 9);
    expect(after[1]).toBeCloseTo(before[1], 9);
  });
  it("fits a rectangle with its margin", () => {
    const c = fit(cam, { minX: 0, minY: 0, maxX: 32000, maxY: 20000 }, 0);
    expect(c.scale).toBe(0.025);
    expect([c.cx, c.cy]).toEqual([16000, 10000]);
    const v = viewBounds(c);
    expect(v.minX).toBe(0);
    expect(v.maxX).toBe(32000);
  });
});
