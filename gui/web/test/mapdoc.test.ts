import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import { MapDocError, parseMapDoc, sameObjects, writeMapDoc } from "../src/editor/mapdoc";
import { elementsOf, parseXml, type XmlElement, XmlError } from "../src/editor/xml";

/** Elements only (whitespace and comments left out): name, attributes in order, children. */
function tree(el: XmlElement): unknown {
  return [el.name, el.attrs, elementsOf(el).map(tree)];
}

describe("map document round trip", () => {
  it("writes the fixture office map back equal, element for element, attributes included", () => {
    const doc = parseMapDoc(office);
    expect(doc.scene.objects.length).toBe(48);
    const back = writeMapDoc(doc);
    expect(tree(parseXml(back))).toEqual(tree(parseXml(office)));
    expect(writeMapDoc(parseMapDoc(back))).toBe(back);
  });
  it("keeps elements and attributes it does not know", () => {
    const src = `<map Version="1.0" vendor="x"><meta owner="me"><note>hi &amp; bye</note></meta>
      <layer index="3" name="walls"><line colour="red"><point x="1" y="2"/><point x="3" y="4"/><tag k="v"/></line>
      <door width="900"><point x="5" y="6"/></door></layer></map>`;
    const doc = parseMapDoc(src);
    expect(doc.scene.objects.map((o) => o.kind)).toEqual(["line", "door"]);
    expect(tree(parseXml(writeMapDoc(doc)))).toEqual(tree(parseXml(src)));
    expect(writeMapDoc(doc)).toContain("<note>hi &amp; bye</note>");
  });
  it("writes an edited label's text and a circle's centre and radius", () => {
    const doc = parseMapDoc(office);
    const label = doc.scene.objects.find((o) => o.kind === "hiddenlabel");
    const circle = doc.scene.objects.find((o) => o.kind === "circle");
    if (label === undefined || circle === undefined) throw new Error("fixture changed");
    label.text = `Kitchen <2> "east"`;
    circle.r = 300.5;
    const out = writeMapDoc(doc);
    expect(out).toContain(`<hiddenlabel text="Kitchen &lt;2&gt; &quot;east&quot;"><point x="3500" y="15600"/>`);
    expect(out).toContain(`<circle><center x="3500" y="16000"/><radius r="300.5"/></circle>`);
  });
});

describe("bad documents", () => {
  const bad: Array<[string, RegExp]> = [
    ["", /no root element/],
    ["<map><layer></map>", /closes <layer>/],
    ["<roadmap/>", /expected a <map> document, got <roadmap>/],
    [`<map><layer><line><point x="a" y="1"/></line></layer></map>`, /<line> has a <point> without a number in x/],
    [`<!DOCTYPE map [<!ENTITY a "b">]><map/>`, /DOCTYPE/],
    [`<map a="1" a="2"/>`, /repeats the attribute a/],
    [`<map>&bogus;</map>`, /unknown entity/],
    [`<map/><map/>`, /second root/],
  ];
  for (const [src, reason] of bad) {
    it(`refuses ${JSON.stringify(src).slice(0, 40)} in one line`, () => {
      expect(() => parseMapDoc(src)).toThrow(MapDocError);
      expect(() => parseMapDoc(src)).toThrow(reason);
    });
  }
  it("says on which line", () => {
    expect(() => parseXml("<map>\n<layer>\n</map>")).toThrow(new XmlError("line 3: </map> closes <layer>"));
  });
});

describe("after sending", () => {
  it("the platform's map is the same when every object, attribute and point is", () => {
    const a = `<map Version="1.0"><layer index="0"><line x="1"><point x="0" y="0"/><point x="5" y="0"/></line></layer></map>`;
    const spaced = `<?xml version="1.0"?>\n<map Version="1.0">\n  <layer index="0">\n    <line x="1"><point x="0.0" y="0"/><point x="5" y="0"/></line>\n  </layer>\n</map>`;
    expect(sameObjects(a, spaced)).toBe(true);
    expect(sameObjects(a, a.replace('x="5"', 'x="6"'))).toBe(false);
    expect(sameObjects(a, a.replace('<line x="1">', "<line>"))).toBe(false);
    expect(sameObjects(a, "")).toBe(false);
    expect(sameObjects("<map", "<map")).toBe(false);
  });
});
