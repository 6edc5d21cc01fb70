import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import { type MapDoc, parseMapDoc, parseMapDocXml } from "../src/editor/mapdoc";
import { readMapFast } from "../src/editor/mapfast";

/** What a reader gives: the document, or the error's class and message. */
function outcome(read: () => MapDoc): unknown {
  try {
    return read();
  } catch (e) {
    return `${(e as Error).constructor.name}: ${(e as Error).message}`;
  }
}

function walls(n: number, seed = 3): string {
  let s = seed;
  const rnd = (): number => (s = (s * 1103515245 + 12345) % 2147483648) / 2147483648;
  const lines: string[] = [];
  for (let i = 0; i < n; i++) {
    const x = Math.round(rnd() * 250000),
      y = Math.round(rnd() * 250000);
    lines.push(`<line><point x="${x}" y="${y}"/><point x="${x + Math.round(rnd() * 3000)}" y="${y - 17}"/></line>`);
  }
  return `<?xml version="1.0"?><map Version="1.0"><layer index="0">${lines.join("")}</layer></map>`;
}

const KEPT = `<map Version="1.0" vendor="x">
  <!-- a comment -->
  <layer index="3" name="walls"><line colour="red"><point x="1" y="2"/><point x="3" y="4" z="9"/><tag k="v"/></line>
    <door width="900"><point x="5" y="6"/></door><circle><center x="1" y="1"/><radius r="5"/><radius r="6"/></circle>
    <hiddenlabel text="Hall"><point x="7" y="8"/></hiddenlabel><hiddenlabel><point x="7" y="8"/></hiddenlabel>
    <empty/><hiddenpolygon><point x="-0" y="1e3"/><point x=" 12 " y="0x10"/><point x="1234567890123456789" y="-12.5"/>
    <point x="+5" y="007"/><point x="999999999999999" y="-999999999999999"/></hiddenpolygon></layer>
  <layer index="1"/>
</map>
<?pi after?>`;

describe("the fast map reader", () => {
  it("reads the fixture office map and a map of random walls exactly as the general reader", () => {
    for (const src of [office, walls(2000), KEPT]) {
      const fast = readMapFast(src, "n");
      expect(fast).not.toBeNull(); // the fast path is taken for these: the comparison below is not vacuous
      expect(fast).toEqual(parseMapDocXml(src, "n"));
    }
  }, 60_000);

  it("gives up where the document leaves the platform's form, so the general reader answers", () => {
    const leave = [
      KEPT.replace("<empty/>", "<empty>text</empty>"), // a child with content
      KEPT.replace('vendor="x"', 'vendor="a &amp; b"'), // an entity
      KEPT.replace("<!-- a comment -->", "<meta/>"), // an element beside the layers
      KEPT.replace('x="1" y="2"', 'x="a" y="2"'), // a bad number
      KEPT.replace('<layer index="1"/>', '<layer index="1.5"/>'), // a bad layer index
      KEPT.replace("</door>", "</dor>"), // malformed
      KEPT.replace('colour="red"', 'colour="red" colour="blue"'), // a repeated attribute
      KEPT.replace("<?pi after?>", "<map/>"), // a second root
      KEPT.replace("<?pi after?>", "<!-- unterminated"),
      "<!DOCTYPE map><map/>",
      "",
    ];
    for (const src of leave) {
      expect(readMapFast(src, "")).toBeNull();
      expect(outcome(() => parseMapDoc(src))).toEqual(outcome(() => parseMapDocXml(src)));
    }
  });

  it("agrees with the general reader on every cut and on every deleted character of a small map", () => {
    const src = KEPT;
    for (let k = 0; k <= src.length; k++) {
      for (const variant of [src.slice(0, k), src.slice(0, k) + src.slice(k + 1)]) {
        expect(outcome(() => parseMapDoc(variant))).toEqual(outcome(() => parseMapDocXml(variant)));
      }
    }
  }, 60_000);
});
