import { describe, expect, it } from "vitest";
import office from "../../../fixtures/roadmaps/office.rm?raw";
import {
  addEdge,
  addStation,
  clearRoadmap,
  deleteStation,
  moveStation,
  newRoadmapDoc,
  parseRoadmapDoc,
  RoadmapDocError,
  RoadmapHistory,
  sameRoadmap,
  writeRoadmapDoc,
} from "../src/editor/roadmapdoc";
import { parseMapDoc, writeMapDoc } from "../src/editor/mapdoc";
import { objectAtLine } from "../src/editor/validate";
import { elementsOf, parseXml, type XmlElement } from "../src/editor/xml";

function tree(el: XmlElement): unknown {
  return [el.name, el.attrs, elementsOf(el).map(tree)];
}

describe("roadmap document", () => {
  it("writes the fixture office roadmap back equal, element for element, attributes included", () => {
    const doc = parseRoadmapDoc(office);
    expect([doc.stations.length, doc.edges.length]).toEqual([18, 17]);
    expect(tree(parseXml(writeRoadmapDoc(doc)))).toEqual(tree(parseXml(office)));
  });
  it("keeps what it does not model, reads bare edge points (E-XML-003)", () => {
    const src = `<roadmap Version="1.0" v="x"><stations><station id="a" name="A" angle="0" prio="2"><point x="1" y="2"/></station>
      <station id="b" name="B" angle="90"><point x="3" y="4"/></station></stations>
      <edges><edge startstation="a" endstation="b" speed="3"><point x="5" y="6"/></edge></edges><meta k="v"/></roadmap>`;
    const doc = parseRoadmapDoc(src);
    expect(doc.edges[0].points).toEqual([5, 6]);
    const back = parseXml(writeRoadmapDoc(doc));
    expect(back.attrs).toEqual([
      ["Version", "1.0"],
      ["v", "x"],
    ]);
    expect(writeRoadmapDoc(doc)).toContain('<station id="a" name="A" angle="0" prio="2">');
    expect(writeRoadmapDoc(doc)).toContain('<edge startstation="a" endstation="b" speed="3">');
    expect(writeRoadmapDoc(doc)).toContain('<points><point x="5" y="6"/></points>');
    expect(writeRoadmapDoc(doc)).toContain('<meta k="v"/>');
  });
  it("refuses another kind of document and a station without a point, with a one-line reason", () => {
    expect(() => parseRoadmapDoc("<map/>")).toThrow(new RoadmapDocError("expected a <roadmap> document, got <map>"));
    expect(() => parseRoadmapDoc('<roadmap><stations><station id="a"/></stations><edges/></roadmap>')).toThrow(
      'station "a" has no <point>',
    );
  });
  it("undo and redo restore exact documents; an impossible edit changes nothing", () => {
    const h = new RoadmapHistory(newRoadmapDoc());
    expect(h.run(addStation("A", 1000, 2000, 90))).toBeNull();
    expect(h.run(addStation("B", 3000, 2000, 0))).toBeNull();
    expect(h.run(addStation("A", 0, 0, 0))).toBe("there is already a station named A");
    expect(h.run(addStation("two words", 0, 0, 0))).toMatch(/one word/);
    expect(h.run(addEdge("s1", "s1"))).toBe("an edge joins two different stations");
    expect(h.run(addEdge("s1", "s2"))).toBeNull();
    expect(h.run(addEdge("s2", "s1"))).toBe("these stations are already joined");
    const built = writeRoadmapDoc(h.doc);
    expect(h.run(moveStation("s1", 1010, 2020))).toBeNull();
    expect(h.doc.stations[0]).toMatchObject({ x: 1010, y: 2020 });
    expect(h.run(deleteStation("s2"))).toBeNull();
    expect(h.doc.edges).toEqual([]);
    expect(h.run(clearRoadmap)).toBeNull();
    h.undo();
    h.undo();
    h.undo();
    expect(writeRoadmapDoc(h.doc)).toBe(built);
    h.redo();
    expect(h.doc.stations[0]).toMatchObject({ id: "s1", x: 1010, y: 2020, angle: 90 });
    expect(h.dirty).toBe(true);
    h.markSaved();
    expect(h.dirty).toBe(false);
  });
});

describe("the object at a line of the written map", () => {
  it("names the object on each object line, null elsewhere, layers in document order", () => {
    const doc =
      parseMapDoc(`<map Version="1.0"><layer index="1"><circle><center x="1" y="1"/><radius r="5"/></circle></layer>
      <layer index="0"><line><point x="0" y="0"/></line><line><point x="0" y="0"/><point x="9" y="9"/></line></layer></map>`);
    const xml = writeMapDoc(doc);
    const lines = xml.split("\n");
    expect(lines[3]).toBe('    <circle><center x="1" y="1"/><radius r="5"/></circle>');
    expect(objectAtLine(doc, xml, 4)).toBe(0);
    expect(objectAtLine(doc, xml, 7)).toBe(1);
    expect(objectAtLine(doc, xml, 8)).toBe(2);
    expect([1, 2, 3, 5, 6, 9].map((n) => objectAtLine(doc, xml, n))).toEqual([null, null, null, null, null, null]);
  });
});

describe("after sending", () => {
  it("the platform's roadmap is the same when it reads and writes the same", () => {
    expect(sameRoadmap(office, office.replace(/\n\s*/g, ""))).toBe(true);
    expect(sameRoadmap(office, office.replace('name="Kitchen"', 'name="Kitchen2"'))).toBe(false);
    expect(sameRoadmap(office, "<map/>")).toBe(false);
  });
});
