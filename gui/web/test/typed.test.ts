import { describe, expect, it } from "vitest";
import { applyFields, fieldsOf } from "../src/editor/typed";
import type { MapObject } from "../src/scene/map";

const line: MapObject = { id: 1, kind: "line", layer: 0, points: [1000, 2000, 4000, 6000], attrs: {} };
const circle: MapObject = { id: 2, kind: "circle", layer: 1, points: [3500, 16000], r: 250, attrs: { note: "pillar" } };
const label: MapObject = {
  id: 3,
  kind: "hiddenlabel",
  layer: 2,
  points: [10, 20],
  text: "Lab",
  attrs: { text: "Lab" },
};
const zone: MapObject = { id: 4, kind: "prohibit", layer: 0, points: [0, 0, 100, 0, 100, 100, 0, 100], attrs: {} };

describe("typed coordinates", () => {
  it("shows points in mm and a line's length and direction in degrees", () => {
    expect(fieldsOf(line)).toEqual({
      x1: "1000",
      y1: "2000",
      x2: "4000",
      y2: "6000",
      length: "5000",
      direction: "53.13",
    });
    expect(fieldsOf(circle)).toEqual({ x1: "3500", y1: "16000", r: "250" });
    expect(fieldsOf(label)).toEqual({ x1: "10", y1: "20", text: "Lab" });
    expect(Object.keys(fieldsOf(zone))).toEqual(["x1", "y1", "x2", "y2", "x3", "y3", "x4", "y4"]);
  });
  it("unchanged fields give the object's geometry back exactly", () => {
    const f = fieldsOf(line);
    expect(applyFields(line, f, { ...f })).toEqual({ ok: true, value: { points: [1000, 2000, 4000, 6000] } });
  });
  it("typed points move the object", () => {
    const f = fieldsOf(line);
    expect(applyFields(line, f, { ...f, x1: "1500", y2: "-250.5" })).toEqual({
      ok: true,
      value: { points: [1500, 2000, 4000, -250.5] },
    });
  });
  it("a typed length and direction place the second point from the first", () => {
    const f = fieldsOf(line);
    expect(applyFields(line, f, { ...f, length: "2000", direction: "90" })).toEqual({
      ok: true,
      value: { points: [1000, 2000, 1000, 4000] },
    });
    expect(applyFields(line, f, { ...f, direction: "180", length: "3000" })).toEqual({
      ok: true,
      value: { points: [1000, 2000, -2000, 2000] },
    });
    expect(applyFields(line, f, { ...f, direction: "45", length: "1000" })).toEqual({
      ok: true,
      value: { points: [1000, 2000, 1707.106781, 2707.106781] },
    });
  });
  it("a circle's radius and a label's text", () => {
    const fc = fieldsOf(circle);
    expect(applyFields(circle, fc, { ...fc, r: "400" })).toEqual({
      ok: true,
      value: { points: [3500, 16000], r: 400 },
    });
    expect(applyFields(circle, fc, { ...fc, r: "0" })).toEqual({
      ok: false,
      reason: "the radius must be more than 0 mm",
    });
    const fl = fieldsOf(label);
    expect(applyFields(label, fl, { ...fl, text: " Store " })).toEqual({
      ok: true,
      value: { points: [10, 20], text: "Store" },
    });
    expect(applyFields(label, fl, { ...fl, text: "" })).toEqual({ ok: false, reason: "a label needs a text" });
  });
  it("bad input says why", () => {
    const f = fieldsOf(line);
    expect(applyFields(line, f, { ...f, x2: "abc" })).toEqual({ ok: false, reason: 'X2 (mm) is not a number: "abc"' });
    expect(applyFields(line, f, { ...f, y1: "" })).toEqual({ ok: false, reason: 'Y1 (mm) is not a number: ""' });
    expect(applyFields(line, f, { ...f, x1: "4000", y1: "6000" })).toEqual({
      ok: false,
      reason: "the line would have zero length",
    });
    expect(applyFields(line, f, { ...f, length: "-5" })).toEqual({
      ok: false,
      reason: "the length must be more than 0 mm",
    });
    expect(applyFields(line, f, { ...f, x1: "3000000000" })).toEqual({
      ok: false,
      reason: "X1 (mm) 3000000000 is outside the map's range (±2147483647 mm)",
    });
    const fz = fieldsOf(zone);
    expect(applyFields(zone, fz, { ...fz, y3: "0", y4: "0" })).toEqual({
      ok: false,
      reason: "the polygon would have no area: its vertices lie on one line",
    });
  });
});
