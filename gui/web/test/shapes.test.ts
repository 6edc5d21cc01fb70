import { describe, expect, it } from "vitest";
import {
  circleObject,
  labelObject,
  measure,
  objectsAt,
  polygonEdgeAt,
  polygonObject,
  segmentObject,
  signedArea2,
  vertexAt,
} from "../src/editor/shapes";
import type { MapObject } from "../src/scene/map";

describe("object tools", () => {
  it("a reflector is a two-point <reflmark>; a zero-length one is refused", () => {
    expect(segmentObject("reflmark", { x: 100, y: 200 }, { x: 100, y: 700 })).toEqual({
      ok: true,
      value: { kind: "reflmark", layer: 0, points: [100, 200, 100, 700], attrs: {} },
    });
    expect(segmentObject("reflmark", { x: 5, y: 5 }, { x: 5, y: 5 })).toEqual({
      ok: false,
      reason: "the reflector has zero length",
    });
    expect(segmentObject("line", { x: 0, y: 0 }, { x: 3e9, y: 0 })).toEqual({
      ok: false,
      reason: "3000000000 mm is outside the map's range (±2147483647 mm)",
    });
  });
  it("a circle is centered where the drag began, its radius on the grid", () => {
    expect(circleObject({ x: 1000, y: 2000 }, { x: 1300, y: 2400 }, 10)).toEqual({
      ok: true,
      value: { kind: "circle", layer: 0, points: [1000, 2000], r: 500, attrs: {} },
    });
    expect(circleObject({ x: 0, y: 0 }, { x: 14, y: 14 }, 10)).toMatchObject({ ok: true, value: { r: 20 } });
    expect(circleObject({ x: 0, y: 0 }, { x: 3, y: 0 }, 10)).toEqual({
      ok: false,
      reason: "the circle has zero radius: drag away from its center",
    });
  });
  it("a polygon drops repeated clicks and a closing click on its first vertex", () => {
    const clicks = [
      { x: 0, y: 0 },
      { x: 1000, y: 0 },
      { x: 1000, y: 0 },
      { x: 1000, y: 500 },
      { x: 0, y: 0 },
    ];
    expect(polygonObject("prohibit", clicks)).toEqual({
      ok: true,
      value: { kind: "prohibit", layer: 0, points: [0, 0, 1000, 0, 1000, 500], attrs: {} },
    });
    expect(polygonObject("workarea", clicks.slice(0, 3))).toEqual({
      ok: false,
      reason: "a polygon needs 3 vertices or more (got 2)",
    });
    expect(
      polygonObject("hiddenpolygon", [
        { x: 0, y: 0 },
        { x: 10, y: 10 },
        { x: 20, y: 20 },
      ]),
    ).toEqual({
      ok: false,
      reason: "the polygon has no area: its vertices lie on one line",
    });
    expect(signedArea2([0, 0, 1000, 0, 1000, 500])).toBe(1000 * 500);
  });
  it("a label needs its text, kept as the `text` attribute", () => {
    expect(labelObject({ x: 10, y: 20 }, "  Kitchen ")).toEqual({
      ok: true,
      value: { kind: "hiddenlabel", layer: 0, points: [10, 20], text: "Kitchen", attrs: { text: "Kitchen" } },
    });
    expect(labelObject({ x: 0, y: 0 }, " ")).toEqual({
      ok: false,
      reason: "a label needs a text: type it in the label field first",
    });
  });
});

describe("vertices and measuring", () => {
  const objs: MapObject[] = [
    { id: 3, kind: "line", layer: 0, points: [0, 0, 1000, 0], attrs: {} },
    { id: 7, kind: "prohibit", layer: 0, points: [990, 5, 2000, 0, 2000, 1000], attrs: {} },
  ];
  it("the nearest vertex within the tolerance, of the selection first", () => {
    expect(vertexAt(objs, 992, 4, 20)).toEqual({ id: 7, vertex: 0 });
    expect(vertexAt(objs, 992, 4, 20, new Set([3]))).toEqual({ id: 3, vertex: 1 });
    expect(vertexAt(objs, 1990, 990, 20)).toEqual({ id: 7, vertex: 2 });
    expect(vertexAt(objs, 500, 500, 20)).toBeNull();
  });
  it("distance and direction between two points", () => {
    expect(measure({ x: 0, y: 0 }, { x: 3000, y: 4000 })).toEqual({ distance: 5000, dx: 3000, dy: 4000, angle: 53.1 });
    expect(measure({ x: 100, y: 0 }, { x: 0, y: 0 })).toEqual({ distance: 100, dx: -100, dy: 0, angle: 180 });
    expect(measure({ x: 0, y: 0 }, { x: 0, y: -250 })).toEqual({ distance: 250, dx: 0, dy: -250, angle: -90 });
    expect(measure({ x: 7, y: 7 }, { x: 7, y: 7 })).toEqual({ distance: 0, dx: 0, dy: 0, angle: 0 });
  });
});

describe("polygon edges", () => {
  const objs: MapObject[] = [
    { id: 1, kind: "line", layer: 0, points: [0, 50, 1000, 50], attrs: {} },
    { id: 2, kind: "prohibit", layer: 0, points: [0, 0, 1000, 0, 1000, 1000, 0, 1000], attrs: {} },
  ];
  it("the edge of a polygon under the pointer, the closing edge included; lines are not polygons", () => {
    expect(polygonEdgeAt(objs, 500, 10, 20)).toEqual({ id: 2, after: 0 });
    expect(polygonEdgeAt(objs, 1010, 500, 20)).toEqual({ id: 2, after: 1 });
    expect(polygonEdgeAt(objs, -5, 500, 20)).toEqual({ id: 2, after: 3 });
    expect(polygonEdgeAt(objs, 500, 50, 20, new Set([1]))).toBeNull();
    expect(polygonEdgeAt(objs, 500, 500, 20)).toBeNull();
  });
});

describe("objects under the pointer", () => {
  const objs: MapObject[] = [
    { id: 5, kind: "line", layer: 0, points: [0, 11200, 4400, 11200], attrs: {} },
    { id: 9, kind: "circle", layer: 1, points: [2000, 11720], r: 500, attrs: {} },
    { id: 40, kind: "hiddenpolygon", layer: 2, points: [0, 8800, 3000, 8800, 3000, 11200, 0, 11200], attrs: {} },
  ];
  it("nearest first, the later object first on a tie; a circle by its rim", () => {
    expect(objectsAt(objs, 1000, 11200, 50)).toEqual([40, 5]);
    expect(objectsAt(objs, 1000, 11190, 50)).toEqual([40, 5]);
    expect(objectsAt(objs, 2000, 11215, 50)).toEqual([9, 40, 5]);
    expect(objectsAt(objs, 3500, 11230, 50)).toEqual([5]);
    expect(objectsAt(objs, 2000, 11720, 50)).toEqual([]);
  });
});
