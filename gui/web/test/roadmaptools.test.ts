// The roadmap editor's tools as named functions (issue 31), on the office roadmap in a real RoadmapHistory, as the
// panel calls them from the map view's pointer events (world mm, 0.1 px per mm: a 100 mm hit radius): what they
// leave in the document, in the selection, and what they say.
import { describe, expect, it } from "vitest";
import office from "../../../fixtures/roadmaps/office.rm?raw";
import { parseRoadmapDoc, RoadmapHistory } from "../src/editor/roadmapdoc";
import {
  applyTyped,
  deleteSelected,
  dragMoved,
  PRESS,
  type RmTool,
  type RoadmapEditing,
  type RoadmapToolEnv,
  release,
  roadmapEditing,
  stationAt,
  toScene,
} from "../src/editor/roadmaptools";

const PX_PER_MM = 0.1;

function setup(fields = { name: "", angle: "" }) {
  const history = new RoadmapHistory(parseRoadmapDoc(office));
  const ed = roadmapEditing(() => history);
  const said: string[] = [];
  const env: RoadmapToolEnv = {
    say: (s) => said.push(s),
    text: (key, words) => (words === undefined ? key : `${key} ${JSON.stringify(words)}`),
    refresh: () => undefined,
    fields: () => fields,
  };
  return { history, ed, env, said, fields };
}

/** A press of `tool`, then (for a drag) moves and the release at the last point. */
function gesture(
  ed: RoadmapEditing,
  env: RoadmapToolEnv,
  tool: RmTool,
  pts: Array<[number, number]>,
  button = 0,
): void {
  ed.tool = tool;
  PRESS[tool](ed, env, pts[0][0], pts[0][1], PX_PER_MM, button);
  if (pts.length > 1) dragMoved(ed);
  const [x, y] = pts[pts.length - 1];
  release(ed, env, x, y);
}

const station = (h: RoadmapHistory, id: string) => h.doc.stations.find((s) => s.id === id);

describe("the roadmap's tools", () => {
  it("Select picks the station under the pointer and a drag places it on the grid", () => {
    const { history, ed, env, said } = setup();
    gesture(ed, env, "select", [
      [1040, 10030],
      [2000, 3000],
      [3004, 4996],
    ]);
    expect(ed.selected).toBe("c_west");
    expect([station(history, "c_west")?.x, station(history, "c_west")?.y]).toEqual([3000, 5000]);
    expect([said.at(-1), history.label]).toEqual(["rm.moved", { key: "act.moveStation" }]);
  });

  it("a click that does not move changes nothing", () => {
    const { history, ed, env } = setup();
    gesture(ed, env, "select", [[5000, 10000]]);
    expect([ed.selected, history.canUndo]).toEqual(["c_01", false]);
  });

  it("Add station names it from the field (else Station_n), on the grid, and selects it; a taken name is refused", () => {
    const { history, ed, env, said, fields } = setup();
    gesture(ed, env, "addStation", [[12345, 6789]]);
    const added = history.doc.stations.find((s) => s.name === "Station_19");
    expect([added?.x, added?.y, ed.selected === added?.id]).toEqual([12350, 6790, true]);
    Object.assign(fields, { name: "Dock", angle: "45" });
    gesture(ed, env, "addStation", [[100, 100]]);
    expect(history.doc.stations.find((s) => s.name === "Dock")?.angle).toBe(45);
    gesture(ed, env, "addStation", [[300, 300]]);
    expect(said.at(-1)).toBe("there is already a station named Dock");
  });

  it("Add edge joins the two stations clicked; a second edge between them is refused", () => {
    const { history, ed, env, said } = setup();
    const n = history.doc.edges.length;
    gesture(ed, env, "addEdge", [[1000, 10000]]);
    expect(ed.edgeFrom).toBe("c_west");
    gesture(ed, env, "addEdge", [[31200, 10000]]);
    expect([history.doc.edges.length, ed.edgeFrom, said.at(-1)]).toEqual([n + 1, null, "rm.edgeAdded"]);
    gesture(ed, env, "addEdge", [[31200, 10000]]);
    gesture(ed, env, "addEdge", [[1000, 10000]]);
    expect(said.at(-1)).toBe("these stations are already joined");
  });

  it("Path points: an edge selected, a point added on the grid, dragged, deleted by a right-click", () => {
    const { history, ed, env, said } = setup();
    gesture(ed, env, "pathPoints", [[3000, 10020]]);
    expect([ed.edgeSel, said.at(-1)]).toEqual([0, 'rm.edgeSelected {"from":"Corridor_W","to":"Corridor_01","n":0}']);
    gesture(ed, env, "pathPoints", [[3004, 9004]]);
    expect(history.doc.edges[0].points).toEqual([3000, 9000]);
    gesture(ed, env, "pathPoints", [
      [3000, 9000],
      [3100, 9100],
      [3196, 8802],
    ]);
    expect(history.doc.edges[0].points).toEqual([3200, 8800]);
    gesture(ed, env, "pathPoints", [[3200, 8800]], 2);
    expect(history.doc.edges[0].points).toEqual([]);
    expect(said.at(-1)).toBe('rm.pathChanged {"from":"Corridor_W","to":"Corridor_01","n":0}');
  });

  it("Path points says when no edge is selected", () => {
    const { ed, env, said } = setup();
    gesture(ed, env, "pathPoints", [[16000, 2000]]);
    expect(said.at(-1)).toBe("rm.noEdge");
  });
});

describe("the roadmap's actions", () => {
  it("Delete and Apply say so when no station is selected", () => {
    const { ed, env, said } = setup();
    deleteSelected(ed, env);
    applyTyped(ed, env, { name: "", x: "1", y: "2", angle: "3" });
    expect(said).toEqual(["edit.noneSelected", "edit.noneSelected"]);
  });

  it("Apply sets the typed pose and name, keeps the name when empty, refuses what is not a number", () => {
    const { history, ed, env, said } = setup();
    ed.selected = "c_01";
    applyTyped(ed, env, { name: "Door", x: "5100", y: "9900", angle: "" });
    expect(station(history, "c_01")).toMatchObject({ name: "Door", x: 5100, y: 9900, angle: 0 });
    applyTyped(ed, env, { name: " ", x: "1", y: "2", angle: "30" });
    expect(station(history, "c_01")).toMatchObject({ name: "Door", x: 1, y: 2, angle: 30 });
    applyTyped(ed, env, { name: "", x: "east", y: "2", angle: "0" });
    expect(said.at(-1)).toBe("rm.badPose");
  });

  it("Delete removes the selected station with its edges, one undoable step", () => {
    const { history, ed, env } = setup();
    const edges = history.doc.edges.length;
    ed.selected = "c_01";
    deleteSelected(ed, env);
    expect(stationAt(history.doc, 5000, 10000, 10)).toBeNull();
    expect(history.doc.edges.length).toBeLessThan(edges);
    expect([ed.selected, ed.edgeSel]).toEqual([null, null]);
    expect(history.undo()).toEqual({ key: "act.deleteStation" });
    expect(history.doc.edges.length).toBe(edges);
  });

  it("the view's roadmap is a copy of the document's stations and edges", () => {
    const { history } = setup();
    const scene = toScene(history.doc, "office");
    expect([scene.name, scene.stations.length, scene.edges.length]).toEqual(["office", 18, 17]);
    scene.edges[9].points.push(1, 2);
    expect(history.doc.edges[9].points.length).toBe(2);
  });
});
