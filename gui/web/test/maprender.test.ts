import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import { parseMapDoc } from "../src/editor/mapdoc";
import { pack, preparePacked } from "../src/view/maprender";
import { countKinds, sceneBounds } from "../src/scene/map";

describe("pack", () => {
  it("counts the objects per kind in its one pass as countKinds does, and takes the bounds it is given", () => {
    const scene = parseMapDoc(office.replace("</layer>", '<door><point x="1" y="2"/></door></layer>')).scene;
    const p = pack(scene);
    expect(p.kinds).toEqual(countKinds(scene));
    expect(p.kinds.door).toBe(1);
    expect(p.bounds).toEqual(sceneBounds(scene));
    const given = { minX: -1, minY: -2, maxX: 3, maxY: 4 };
    expect(pack(scene, given).bounds).toBe(given);
  });
  it("builds a kind's grid only when it is first asked for, and then the same one", () => {
    const prep = preparePacked(pack(parseMapDoc(office).scene));
    const lines = prep.lines.get("line")!;
    expect(lines.n).toBeGreaterThan(0);
    expect(lines.grid).toBe(lines.grid);
    expect(lines.grid.n).toBe(lines.n);
  });
});
