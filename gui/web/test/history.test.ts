// One history interface for both editors (issue 31): the map's command history (commands.ts) and the roadmap's
// snapshot history (roadmapdoc.ts) answer the same questions the same way: undo and redo with their labels,
// what can be undone, and whether the document differs from the one saved (or sent).
import { describe, expect, it } from "vitest";
import mapSrc from "../../../fixtures/maps/office.map?raw";
import rmSrc from "../../../fixtures/roadmaps/office.rm?raw";
import { History, moveObjects } from "../src/editor/commands";
import type { Action, EditHistory } from "../src/editor/history";
import type { Key } from "../src/i18n/i18n";

/** A step named `s` (a stand-in for a catalog key). */
const L = (s: string): Action => ({ key: s as Key });
import { parseMapDoc, writeMapDoc } from "../src/editor/mapdoc";
import { addStation, parseRoadmapDoc, RoadmapHistory, writeRoadmapDoc } from "../src/editor/roadmapdoc";

/** A history, a way to make an edit labelled `label`, and the document as text. */
interface Subject {
  history: EditHistory;
  edit(label: string): void;
  text(): string;
}

const SUBJECTS: Record<string, () => Subject> = {
  "map (commands)": () => {
    const h = new History(parseMapDoc(mapSrc));
    let k = 0;
    return {
      history: h,
      edit: (label) => h.run({ label: L(label), changes: moveObjects(h.doc, [1], 10 * ++k, 0).changes }),
      text: () => writeMapDoc(h.doc),
    };
  },
  "roadmap (snapshots)": () => {
    const h = new RoadmapHistory(parseRoadmapDoc(rmSrc));
    let k = 0;
    return {
      history: h,
      edit: (label) => {
        k++;
        expect(h.run(addStation(`S${k}`, 100 * k, 0, 0), L(label))).toBeNull();
      },
      text: () => writeRoadmapDoc(h.doc),
    };
  },
};

describe.each(Object.entries(SUBJECTS))("the history of the %s editor", (_name, make) => {
  it("has nothing to undo or redo at first, and the document is not dirty", () => {
    const s = make();
    expect([s.history.canUndo, s.history.canRedo, s.history.label, s.history.dirty]).toEqual([
      false,
      false,
      null,
      false,
    ]);
    expect(s.history.undo()).toBeNull();
    expect(s.history.redo()).toBeNull();
  });

  it("undoes and redoes by label, and the label is the last action done", () => {
    const s = make();
    const before = s.text();
    s.edit("first");
    const afterFirst = s.text();
    s.edit("second");
    const afterSecond = s.text();
    expect(s.history.label).toEqual(L("second"));
    expect(s.history.undo()).toEqual(L("second"));
    expect(s.text()).toBe(afterFirst);
    expect([s.history.label, s.history.canUndo, s.history.canRedo]).toEqual([L("first"), true, true]);
    expect(s.history.undo()).toEqual(L("first"));
    expect(s.text()).toBe(before);
    expect([s.history.label, s.history.canUndo]).toEqual([null, false]);
    expect(s.history.redo()).toEqual(L("first"));
    expect(s.history.redo()).toEqual(L("second"));
    expect(s.text()).toBe(afterSecond);
    expect(s.history.canRedo).toBe(false);
  });

  it("drops what was undone at a new action", () => {
    const s = make();
    s.edit("a");
    s.history.undo();
    s.edit("b");
    expect([s.history.canRedo, s.history.redo(), s.history.label]).toEqual([false, null, L("b")]);
  });

  it("is dirty until saved, again after an undo, clean when redone to the saved document", () => {
    const s = make();
    s.edit("a");
    expect(s.history.dirty).toBe(true);
    s.history.markSaved();
    expect(s.history.dirty).toBe(false);
    s.history.undo();
    expect(s.history.dirty).toBe(true);
    s.history.redo();
    expect(s.history.dirty).toBe(false);
  });

  it("is dirty after another action at the saved depth (the old roadmap history counted steps only)", () => {
    const s = make();
    s.edit("a");
    s.history.markSaved();
    s.history.undo();
    s.edit("b");
    expect(s.history.dirty).toBe(true);
  });

  it("is unbounded: 300 actions undone give back the document exactly", () => {
    const s = make();
    const before = s.text();
    for (let k = 0; k < 300; k++) {
      s.edit(`e${k}`);
    }
    let n = 0;
    while (s.history.undo() !== null) {
      n++;
    }
    expect(n).toBe(300);
    expect(s.text()).toBe(before);
    expect(s.history.dirty).toBe(false);
  });
});
