import { describe, expect, it } from "vitest";
import { act } from "../src/editor/history";
import office from "../../../fixtures/maps/office.map?raw";
import {
  addObject,
  addObjects,
  addReplacing,
  clearMap,
  deleteObjects,
  deleteVertex,
  insertVertex,
  History,
  invertLine,
  lineOp,
  moveObjects,
  moveVertex,
  setGeometry,
} from "../src/editor/commands";
import { extend, trim } from "../src/editor/geometry";
import { parseMapDoc, writeMapDoc } from "../src/editor/mapdoc";

const fresh = (): History => new History(parseMapDoc(office));
const snapshot = (h: History): string => JSON.stringify(h.doc.scene.objects);
const pointsOf = (h: History, id: number): number[] => {
  const o = h.doc.scene.objects.find((x) => x.id === id);
  if (o === undefined) throw new Error(`no object ${id}`);
  return o.points;
};

describe("history", () => {
  it("undo and redo restore exact coordinates, unbounded", () => {
    const h = fresh();
    const start = snapshot(h);
    // id 5 is the corridor wall (0,11200)-(4400,11200); id 15 the wall at x = 7000 from y 11200 to 20000
    for (let k = 0; k < 500; k++) {
      h.run(moveObjects(h.doc, [5], 0.1, 0.3));
    }
    expect(pointsOf(h, 5)).toEqual([50, 11350, 4450, 11350]);
    const ext = lineOp(h.doc, act("act.extend"), extend, 5, 15);
    if (!ext.ok) throw new Error(ext.reason);
    h.run(ext.value);
    expect(pointsOf(h, 5)).toEqual([50, 11350, 7000, 11350]);
    const afterAll = snapshot(h);
    while (h.undo() !== null) {
      /* all the way back */
    }
    expect(snapshot(h)).toBe(start);
    expect(pointsOf(h, 5)).toEqual([0, 11200, 4400, 11200]);
    while (h.redo() !== null) {
      /* all the way forward */
    }
    expect(snapshot(h)).toBe(afterAll);
  });
  it("a new command drops the redo branch; dirty follows save, undo and redo", () => {
    const h = fresh();
    expect(h.dirty).toBe(false);
    h.run(moveObjects(h.doc, [1], 10, 0));
    expect(h.dirty).toBe(true);
    h.markSaved();
    expect(h.dirty).toBe(false);
    h.undo();
    expect(h.dirty).toBe(true);
    h.run(moveObjects(h.doc, [1], 0, 10));
    expect(h.canRedo).toBe(false);
    expect(pointsOf(h, 1)).toEqual([0, 10, 32000, 10]);
  });
  it("add, delete and clear keep the document order through undo", () => {
    const h = fresh();
    const start = writeMapDoc(h.doc);
    h.run(addObject(h.doc, { kind: "line", layer: 0, points: [100, 100, 900, 100], attrs: {} }));
    h.run(deleteObjects(h.doc, [3, 40, 7]));
    h.run(
      addObjects(
        h.doc,
        [
          { kind: "linemapped", layer: 1, points: [0, 0, 1000, 0], attrs: {} },
          { kind: "auxlinemapped", layer: 1, points: [0, 0, 0, 300], attrs: {} },
        ],
        act("act.fromScan", { n: 2 }),
      ),
    );
    expect(h.doc.scene.objects.map((o) => o.id).slice(-3)).toEqual([48, 49, 50]);
    h.run(clearMap(h.doc));
    expect(h.doc.scene.objects).toEqual([]);
    expect(writeMapDoc(h.doc)).toContain(`<layer index="0"/>`);
    for (let k = 0; k < 4; k++) h.undo();
    expect(writeMapDoc(h.doc)).toBe(start);
  });
  it("an edit changes only the objects it touches", () => {
    const h = fresh();
    const before = h.doc.scene.objects.slice();
    h.run(moveVertex(h.doc, 0, 2, { x: 31000, y: 19000 }));
    const after = h.doc.scene.objects;
    expect(after[0].points).toEqual([0, 0, 32000, 0, 31000, 19000, 0, 20000]);
    expect(after.filter((o, k) => o !== before[k]).map((o) => o.id)).toEqual([0]);
  });
});

describe("geometric commands", () => {
  it("trim against a parallel line says why and changes nothing", () => {
    const h = fresh();
    const start = snapshot(h);
    const r = lineOp(h.doc, act("act.trim"), trim, 5, 10); // corridor walls y = 11200 and y = 8800
    expect(r).toEqual({ ok: false, reason: "the lines are parallel: they never cross" });
    expect(lineOp(h.doc, act("act.trim"), trim, 5, 5)).toEqual({
      ok: false,
      reason: "the reference line is the line itself",
    });
    expect(lineOp(h.doc, act("act.trim"), trim, 0, 5)).toEqual({ ok: false, reason: "a <workarea> is not a line" });
    expect(snapshot(h)).toBe(start);
  });
  it("invert swaps a line's ends and undo swaps them back", () => {
    const h = fresh();
    const r = invertLine(h.doc, 1);
    if (!r.ok) throw new Error(r.reason);
    h.run(r.value);
    expect(pointsOf(h, 1)).toEqual([32000, 0, 0, 0]);
    h.undo();
    expect(pointsOf(h, 1)).toEqual([0, 0, 32000, 0]);
  });
});

describe("object commands", () => {
  it("typed geometry replaces points, radius and text and keeps other attributes; undo restores it", () => {
    const h = fresh();
    const circle = h.doc.scene.objects.find((o) => o.kind === "circle");
    const label = h.doc.scene.objects.find((o) => o.kind === "hiddenlabel");
    if (circle === undefined || label === undefined) throw new Error("fixture without a circle or a label");
    const start = writeMapDoc(h.doc);
    h.run(setGeometry(h.doc, circle.id, { points: [100, 200], r: 400 }));
    h.run(setGeometry(h.doc, label.id, { points: [5, 6], text: "Store" }));
    const xml = writeMapDoc(h.doc);
    expect(xml).toContain(`<circle><center x="100" y="200"/><radius r="400"/></circle>`);
    expect(xml).toMatch(/<hiddenlabel [^>]*text="Store"[^>]*><point x="5" y="6"\/><\/hiddenlabel>/);
    h.undo();
    h.undo();
    expect(writeMapDoc(h.doc)).toBe(start);
  });
  it("a new workarea replaces the old one in one step", () => {
    const h = fresh();
    const start = writeMapDoc(h.doc);
    const n = h.doc.scene.objects.length;
    h.run(
      addReplacing(
        h.doc,
        { kind: "workarea", layer: 0, points: [0, 0, 10, 0, 10, 10], attrs: {} },
        [0],
        act("act.replaceWorkarea"),
      ),
    );
    const areas = h.doc.scene.objects.filter((o) => o.kind === "workarea");
    expect(areas.map((o) => o.points)).toEqual([[0, 0, 10, 0, 10, 10]]);
    expect(h.doc.scene.objects.length).toBe(n);
    h.undo();
    expect(writeMapDoc(h.doc)).toBe(start);
    h.redo();
    expect(h.doc.scene.objects.filter((o) => o.kind === "workarea").map((o) => o.points)).toEqual([
      [0, 0, 10, 0, 10, 10],
    ]);
  });
});

describe("vertices of polygons", () => {
  it("a vertex is inserted after the given one and deleted again; a polygon keeps 3", () => {
    const h = fresh();
    const zone = h.doc.scene.objects.find((o) => o.kind === "prohibit");
    if (zone === undefined) throw new Error("no prohibit in the fixture");
    const start = [...zone.points];
    const ins = insertVertex(h.doc, zone.id, 1, { x: 15000.0000001, y: 3000 });
    if (!ins.ok) throw new Error(ins.reason);
    h.run(ins.value);
    expect(pointsOf(h, zone.id)).toEqual([11000, 1000, 14500, 1000, 15000, 3000, 14500, 5500, 11000, 5500]);
    for (const k of [2, 0]) {
      const del = deleteVertex(h.doc, zone.id, k);
      if (!del.ok) throw new Error(del.reason);
      h.run(del.value);
    }
    expect(pointsOf(h, zone.id)).toEqual([14500, 1000, 14500, 5500, 11000, 5500]);
    expect(deleteVertex(h.doc, zone.id, 0)).toEqual({
      ok: false,
      reason: "a polygon keeps at least 3 vertices: delete the polygon instead",
    });
    expect(insertVertex(h.doc, 1, 0, { x: 1, y: 1 })).toEqual({
      ok: false,
      reason: "a <line> has a fixed number of points: only a polygon gets new vertices",
    });
    for (let k = 0; k < 3; k++) h.undo();
    expect(pointsOf(h, zone.id)).toEqual(start);
  });
  it("clear keeps the elements the editor does not know", () => {
    const src = `<map Version="1.0"><layer index="0"><line><point x="0" y="0"/><point x="5" y="0"/></line><door w="900"><point x="1" y="2"/></door></layer></map>`;
    const h = new History(parseMapDoc(src));
    h.run(clearMap(h.doc));
    expect(writeMapDoc(h.doc)).toContain(`<door w="900"><point x="1" y="2"/></door>`);
    expect(h.doc.scene.objects.map((o) => o.kind)).toEqual(["door"]);
  });
});
