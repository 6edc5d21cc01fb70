import { describe, expect, it } from "vitest";
import office from "../../../fixtures/roadmaps/office.rm?raw";
import { parseRoadmapDoc, RoadmapHistory, writeRoadmapDoc } from "../src/editor/roadmapdoc";
import {
  deletePathPoint,
  edgeAt,
  edgePath,
  insertPathPoint,
  movePathPoint,
  pathPointAt,
} from "../src/editor/roadmappath";

const fresh = (): RoadmapHistory => new RoadmapHistory(parseRoadmapDoc(office));
// edge 0: c_west (1000,10000) -> c_01 (5000,10000), no path points; edge 9: c_01 -> r_kitchen via (5000,11200)

describe("path points of roadmap edges", () => {
  it("finds the edge and the path point under the pointer", () => {
    const h = fresh();
    expect(edgePath(h.doc, 9)).toEqual([5000, 10000, 5000, 11200, 5000, 12200]);
    expect(edgeAt(h.doc, 3000, 10040, 50)).toBe(0);
    expect(edgeAt(h.doc, 3000, 10100, 50)).toBeNull();
    expect(pathPointAt(h.doc, 5010, 11190, 50)).toEqual({ edge: 9, k: 0 });
    expect(pathPointAt(h.doc, 5000, 11600, 50)).toBeNull();
  });
  it("inserts a point into the nearest piece of the path, moves and deletes it; undo restores the document", () => {
    const h = fresh();
    const start = writeRoadmapDoc(h.doc);
    expect(h.run(insertPathPoint(0, 3000, 9500))).toBeNull();
    expect(h.doc.edges[0].points).toEqual([3000, 9500]);
    expect(h.run(insertPathPoint(0, 2000, 9700))).toBeNull(); // before (3000, 9500): nearer the first piece
    expect(h.run(insertPathPoint(0, 4000, 9700))).toBeNull(); // after it
    expect(h.doc.edges[0].points).toEqual([2000, 9700, 3000, 9500, 4000, 9700]);
    expect(h.run(movePathPoint(0, 1, 3000, 9000))).toBeNull();
    expect(h.run(deletePathPoint(0, 0))).toBeNull();
    expect(h.doc.edges[0].points).toEqual([3000, 9000, 4000, 9700]);
    expect(writeRoadmapDoc(h.doc).replace(/\s*\n\s*/g, "")).toContain(
      `<edge startstation="c_west" endstation="c_01"><points><point x="3000" y="9000"/><point x="4000" y="9700"/></points></edge>`,
    );
    for (let k = 0; k < 5; k++) h.undo();
    expect(writeRoadmapDoc(h.doc)).toBe(start);
  });
  it("a point that is not there says so and changes nothing", () => {
    const h = fresh();
    expect(h.run(movePathPoint(0, 0, 1, 1))).toBe("edge 0 has no path point 0");
    expect(h.run(deletePathPoint(9, 1))).toBe("edge 9 has no path point 1");
    expect(h.run(insertPathPoint(99, 1, 1))).toBe("no edge 99 between two stations of the roadmap");
    expect(h.canUndo).toBe(false);
  });
});
