import { describe, expect, it } from "vitest";
import { act } from "../src/editor/history";
import office from "../../../fixtures/maps/office.map?raw";
import { addObject, addObjects, deleteObjects, History } from "../src/editor/commands";
import { type ToolContext, ShapeTools } from "../src/editor/drawtools";
import { linesFromScan } from "../src/editor/fromscan";
import { defaultLayer, documentLayers, layerChoices } from "../src/editor/layers";
import { newMapDoc, parseMapDoc, writeMapDoc } from "../src/editor/mapdoc";
import { circleObject, labelObject, polygonObject, segmentObject } from "../src/editor/shapes";
import { elementsOf, parseXml, type XmlElement } from "../src/editor/xml";
import type { Result } from "../src/editor/geometry";

/** Each <layer>'s index and its objects' tags and first point, in document order. */
function layersOf(xml: string): Array<[string | undefined, string[]]> {
  return elementsOf(parseXml(xml)).map((l: XmlElement) => [
    l.attrs.find(([k]) => k === "index")?.[1],
    elementsOf(l).map(
      (o) =>
        `${o.name}@${elementsOf(o)[0]
          ?.attrs.map(([, v]) => v)
          .join(",")}`,
    ),
  ]);
}

function value<T>(r: Result<T>): T {
  if (!r.ok) throw new Error(r.reason);
  return r.value;
}

describe("the layer for new objects", () => {
  it("offers the document's layers and the next free index; starts on the first layer of the document", () => {
    const doc = parseMapDoc(office);
    expect(documentLayers(doc)).toEqual([0, 1, 2]);
    expect(defaultLayer(doc)).toBe(0);
    expect(layerChoices(doc, 0)).toEqual([
      { index: 0, fresh: false },
      { index: 1, fresh: false },
      { index: 2, fresh: false },
      { index: 3, fresh: true },
    ]);
    // a new map: layer 0, to be started
    expect(defaultLayer(newMapDoc())).toBe(0);
    expect(layerChoices(newMapDoc(), 0)).toEqual([{ index: 0, fresh: true }]);
    // the first layer in document order, not the lowest index; an empty layer counts
    const doc2 = parseMapDoc(
      `<map><layer index="5"/><layer index="2"><line><point x="0" y="0"/><point x="1" y="0"/></line></layer></map>`,
    );
    expect(defaultLayer(doc2)).toBe(5);
    expect(layerChoices(doc2, 5).map((c) => c.index)).toEqual([2, 5, 6]);
  });
  it("keeps a chosen new layer on offer after its objects are undone", () => {
    const h = new History(parseMapDoc(office));
    h.run(addObject(h.doc, value(segmentObject("line", { x: 0, y: 0 }, { x: 100, y: 0 }, 3))));
    expect(layerChoices(h.doc, 3).map((c) => [c.index, c.fresh])).toEqual([
      [0, false],
      [1, false],
      [2, false],
      [3, false],
      [4, true],
    ]);
    h.run(addObject(h.doc, value(segmentObject("line", { x: 0, y: 0 }, { x: 100, y: 0 }, 4))));
    h.undo();
    h.undo();
    expect(layerChoices(h.doc, 4).map((c) => [c.index, c.fresh])).toEqual([
      [0, false],
      [1, false],
      [2, false],
      [3, true],
      [4, true],
    ]);
  });
  it("builds every kind of new object in the chosen layer", () => {
    const [a, b, c] = [
      { x: 0, y: 0 },
      { x: 1000, y: 0 },
      { x: 0, y: 1000 },
    ];
    expect(value(segmentObject("line", a, b, 2)).layer).toBe(2);
    expect(value(segmentObject("reflmark", a, b, 2)).layer).toBe(2);
    expect(value(circleObject(a, b, 10, 2)).layer).toBe(2);
    for (const kind of ["workarea", "prohibit", "hiddenpolygon"] as const) {
      expect(value(polygonObject(kind, [a, b, c], 2)).layer).toBe(2);
    }
    expect(value(labelObject(a, "Door", 2)).layer).toBe(2);
    const scan = Array.from({ length: 81 }, (_, k) => ({ x: 2000, y: -2000 + 50 * k }));
    const lines = linesFromScan({ estX: 0, estY: 0, estAngle: 0, scan }, { MinLineLenAux: 200, MinLineLenMap: 500 }, 2);
    expect(lines.length).toBe(1);
    expect(lines[0].layer).toBe(2);
  });
  it("the pointer tools take the layer from their context", () => {
    const h = new History(parseMapDoc(office));
    const ctx: ToolContext = {
      doc: () => h.doc,
      run: (r) => h.run(value(r)),
      say: () => undefined,
      snap: (p) => p,
      snapEnd: (p) => p,
      labelText: () => "Door",
      layer: () => 1,
      near: () => h.doc.scene.objects,
      selection: () => new Set(),
      measured: () => "",
      grid: 10,
    };
    const tools = new ShapeTools(ctx);
    for (const tool of ["reflector", "circle"] as const) {
      tools.down(tool, 40000, 0, 1, 0);
      tools.move(tool, 41000, 0);
      tools.up(tool, 41000, 0);
    }
    tools.down("label", 40000, 500, 1, 0);
    for (const p of [
      [40000, 1000],
      [41000, 1000],
      [41000, 2000],
    ])
      tools.down("prohibit", p[0], p[1], 1, 0);
    tools.finish("prohibit");
    expect(h.doc.scene.objects.slice(48).map((o) => [o.kind, o.layer])).toEqual([
      ["reflmark", 1],
      ["circle", 1],
      ["hiddenlabel", 1],
      ["prohibit", 1],
    ]);
  });
});

describe("new objects in the document", () => {
  it("an object added to an existing layer is written at that layer's end, the rest unchanged", () => {
    const h = new History(parseMapDoc(office));
    const start = writeMapDoc(h.doc);
    const before = layersOf(start);
    h.run(addObject(h.doc, value(segmentObject("line", { x: 100, y: 200 }, { x: 900, y: 200 }, 1))));
    const after = layersOf(writeMapDoc(h.doc));
    expect(after[1]).toEqual(["1", [...before[1][1], "line@100,200"]]);
    expect([after[0], after[2]]).toEqual([before[0], before[2]]);
    h.undo();
    expect(writeMapDoc(h.doc)).toBe(start);
  });
  it("a new layer is written after the document's layers while it holds objects; undo removes it again", () => {
    const h = new History(parseMapDoc(office));
    const start = writeMapDoc(h.doc);
    const objs = [
      value(segmentObject("line", { x: 0, y: 0 }, { x: 500, y: 0 }, 3)),
      value(segmentObject("line", { x: 0, y: 100 }, { x: 500, y: 100 }, 3)),
    ];
    h.run(addObjects(h.doc, objs, act("act.fromScan", { n: 4 })));
    const out = writeMapDoc(h.doc);
    expect(layersOf(out).map(([i]) => i)).toEqual(["0", "1", "2", "3"]);
    expect(layersOf(out)[3]).toEqual(["3", ["line@0,0", "line@0,100"]]);
    expect(out).toMatch(/<\/layer>\n {2}<layer index="3">\n {4}<line><point x="0" y="0"\/>/);
    expect(layersOf(out).slice(0, 3)).toEqual(layersOf(start));
    h.undo();
    expect(writeMapDoc(h.doc)).toBe(start);
    h.redo();
    expect(writeMapDoc(h.doc)).toBe(out);
  });
  it("a layer the document had stays when its last object is deleted", () => {
    const h = new History(parseMapDoc(office));
    const inTwo = h.doc.scene.objects.filter((o) => o.layer === 2).map((o) => o.id);
    h.run(deleteObjects(h.doc, inTwo));
    expect(layersOf(writeMapDoc(h.doc))[2]).toEqual(["2", []]);
    expect(documentLayers(h.doc)).toEqual([0, 1, 2]);
  });
  it("a new map's first object starts layer 0", () => {
    const h = new History(newMapDoc());
    h.run(addObject(h.doc, value(labelObject({ x: 5, y: 6 }, "Hall", defaultLayer(h.doc)))));
    expect(layersOf(writeMapDoc(h.doc))).toEqual([["0", ["hiddenlabel@5,6"]]]);
  });
});
