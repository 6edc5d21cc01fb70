// The map editor's tools as named functions (issue 31), on the office map in a real History, as the panel calls
// them from the map view's pointer events (world mm, 1 px per mm here): what they leave in the document, in the
// selection, and what they say.
import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import { History } from "../src/editor/commands";
import { ShapeTools } from "../src/editor/drawtools";
import { parseMapDoc } from "../src/editor/mapdoc";
import { fieldsOf } from "../src/editor/typed";
import type { MapObject } from "../src/scene/map";
import {
  clearAll,
  convertScan,
  deleteSelection,
  type EditTool,
  invertSelected,
  type MapEditing,
  type MapToolEnv,
  mapEditing,
  POINTER,
  run,
  selectAll,
  selection,
  snapped,
  typeCoordinates,
} from "../src/editor/maptools";

function setup(): { ed: MapEditing; env: MapToolEnv; said: string[]; history: History } {
  const history = new History(parseMapDoc(office));
  const ed = mapEditing(() => history);
  const said: string[] = [];
  const env: MapToolEnv = {
    say: (s) => said.push(s),
    text: (key, words) => (words === undefined ? key : `${key} ${JSON.stringify(words)}`),
    refresh: () => undefined,
    layer: () => 0,
    shapes: new ShapeTools({
      doc: () => history.doc,
      run: (r) => run(ed, env, r),
      say: (s) => said.push(s),
      snap: (p, px) => snapped(history, p, px),
      snapEnd: (p, px) => snapped(history, p, px, 0),
      near: (x, y, tol) => history.near(x, y, tol),
      labelText: () => "",
      layer: () => 0,
      selection: () => selection(ed),
      measured: (m) => `measured ${m.distance}`,
      grid: 10,
    }),
  };
  return { ed, env, said, history };
}

/** A press, moves and a release of `tool` at world points (mm), 1 px per mm. */
function gesture(ed: MapEditing, env: MapToolEnv, tool: EditTool, ...pts: Array<[number, number]>): void {
  ed.tool = tool;
  const p = POINTER[tool];
  const [x0, y0] = pts[0];
  p.down(ed, env, x0, y0, 1, 0);
  for (const [x, y] of pts.slice(1)) {
    p.move(ed, env, x, y);
  }
  const [x1, y1] = pts[pts.length - 1];
  p.up(ed, env, x1, y1);
}

const pointsOf = (h: History, id: number): number[] | undefined => h.byId(id)?.points;

describe("Edit objects", () => {
  it("selects the line under the pointer and drags it by whole grid steps", () => {
    const { ed, env, said, history } = setup();
    gesture(ed, env, "select", [4000, 11200], [4000, 11203], [4034, 11247]);
    expect(ed.selected).toBe(5);
    expect(pointsOf(history, 5)).toEqual([30, 11250, 4430, 11250]);
    expect(said.at(-1)).toBe('edit.actionDone {"action":"act.move"}');
    expect(history.label).toEqual({ key: "act.move" });
  });

  it("goes through objects on top of each other at still clicks (a wall on the workarea's edge)", () => {
    const { ed, env } = setup();
    gesture(ed, env, "select", [16000, 0]);
    const first = ed.selected;
    gesture(ed, env, "select", [16000, 0]);
    const second = ed.selected;
    expect(new Set([first, second])).toEqual(new Set([0, 1]));
    gesture(ed, env, "select", [16000, 0]);
    expect(ed.selected).toBe(first);
  });

  it("selects nothing on empty floor, and a drag there moves nothing", () => {
    const { ed, env, history } = setup();
    const before = JSON.stringify(history.doc.scene.objects);
    gesture(ed, env, "select", [3000, 3000], [3500, 3500]);
    expect([ed.selected, history.canUndo, JSON.stringify(history.doc.scene.objects)]).toEqual([null, false, before]);
  });
});

describe("Add a line", () => {
  it("adds a line from the press to the release, snapped to the grid and to endpoints", () => {
    const { ed, env, history } = setup();
    const n = history.doc.scene.objects.length;
    gesture(ed, env, "addLine", [1003, 3004], [2000, 3000], [4402, 11198]);
    const added = history.doc.scene.objects[n];
    expect([added.kind, added.points]).toEqual(["line", [1000, 3000, 4400, 11200]]);
  });

  it("refuses a line of zero length", () => {
    const { ed, env, said, history } = setup();
    gesture(ed, env, "addLine", [1000, 3000], [1002, 3001]);
    expect([said.at(-1), history.canUndo]).toEqual(["the line has zero length", false]);
  });
});

describe("the two-click line operations", () => {
  it("extends the first line clicked to the second", () => {
    const { ed, env, history } = setup();
    gesture(ed, env, "extend", [4000, 11200]);
    expect(ed.first?.id).toBe(5);
    gesture(ed, env, "extend", [7000, 15000]);
    expect([pointsOf(history, 5), ed.first, history.label]).toEqual([
      [0, 11200, 7000, 11200],
      null,
      { key: "act.extend" },
    ]);
  });

  it("says why a trim against a parallel line cannot be done and changes nothing", () => {
    const { ed, env, said, history } = setup();
    gesture(ed, env, "trim", [4000, 11200]);
    gesture(ed, env, "trim", [5000, 8800]);
    expect(said.at(-1)).toMatch(/parallel/);
    expect(history.canUndo).toBe(false);
  });
});

describe("the toolbar's actions", () => {
  it("Delete and Invert say so when nothing is selected", () => {
    const { ed, env, said } = setup();
    deleteSelection(ed, env);
    invertSelected(ed, env);
    expect(said).toEqual(["edit.noneSelected", "edit.noneSelected"]);
  });

  it("Select all then Delete removes every object in one step; Undo brings them back", () => {
    const { ed, env, history } = setup();
    const n = history.doc.scene.objects.length;
    selectAll(ed);
    expect(selection(ed).size).toBe(n);
    deleteSelection(ed, env);
    expect([history.doc.scene.objects.length, selection(ed).size]).toEqual([0, 0]);
    history.undo();
    expect(history.doc.scene.objects.length).toBe(n);
  });

  it("Invert turns the selected line around; Clear removes every object and the selection", () => {
    const { ed, env, history } = setup();
    ed.selected = 5;
    invertSelected(ed, env);
    expect(pointsOf(history, 5)).toEqual([4400, 11200, 0, 11200]);
    clearAll(ed, env);
    expect([history.doc.scene.objects.length, ed.selected]).toEqual([0, null]);
  });

  it("Convert lines from scan says when there is no scan", () => {
    const { ed, env, said } = setup();
    convertScan(ed, env, undefined, []);
    convertScan(ed, env, { scan: [], estX: 0, estY: 0, estPhi: 0 } as never, []);
    expect(said).toEqual(["edit.noScan", "edit.noScan"]);
  });

  it("typed coordinates replace the selected line's points in one step", () => {
    const { ed, env, history } = setup();
    ed.selected = 5;
    const shown = fieldsOf(history.byId(5) as MapObject);
    typeCoordinates(ed, env, { ...shown, x1: "100" }, shown);
    expect(pointsOf(history, 5)?.[0]).toBe(100);
    expect(history.label).toEqual({ key: "act.typed" });
    ed.many = new Set([1, 2]);
    typeCoordinates(ed, env, { ...shown, x1: "5" }, shown);
    expect(history.label).toEqual({ key: "act.typed" });
    expect(history.undo()).toEqual({ key: "act.typed" });
    expect(history.canUndo).toBe(false);
  });
});
