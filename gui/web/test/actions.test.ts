// The history's messages (issue 35): each editor's steps are named by catalog keys (act.*), and Undo and Redo say
// which action they took back or did again ("Undone: add a line"), in English and in German, from the real
// catalogs and the real histories of both editors.
import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import officeRm from "../../../fixtures/roadmaps/office.rm?raw";
import { addAction, addObject, History, lineOp } from "../src/editor/commands";
import { extend } from "../src/editor/geometry";
import { act, actionMessage, type Words } from "../src/editor/history";
import { parseMapDoc } from "../src/editor/mapdoc";
import { addStation, parseRoadmapDoc, RoadmapHistory } from "../src/editor/roadmapdoc";
import { de } from "../src/i18n/de";
import { en, type Key } from "../src/i18n/en";
import { KINDS } from "../src/scene/map";

const CATALOGS = { en, de } as const;

/** The catalog's wording in `lang`, as i18n.ts's `t` does it (without the page's language switch). */
const wording =
  (lang: keyof typeof CATALOGS) =>
  (key: Key, words?: Words): string => {
    let s: string = CATALOGS[lang][key];
    for (const [k, v] of Object.entries(words ?? {})) s = s.replace(`{${k}}`, String(v));
    return s;
  };

describe("the map editor's Undo and Redo name the action", () => {
  it.each([
    ["en", "Done: add a line", "Undone: add a line", "Redone: add a line"],
    ["de", "Ausgeführt: Linie hinzufügen", "Rückgängig gemacht: Linie hinzufügen", "Wiederholt: Linie hinzufügen"],
  ] as const)("in %s", (lang, done, undone, redone) => {
    const text = wording(lang);
    const h = new History(parseMapDoc(office));
    const cmd = addObject(h.doc, { kind: "line", layer: 0, points: [0, 0, 1000, 0], attrs: {} });
    h.run(cmd);
    expect(actionMessage("done", h.label, text)).toBe(done);
    expect(actionMessage("undone", h.undo(), text)).toBe(undone);
    expect(actionMessage("redone", h.redo(), text)).toBe(redone);
  });

  it("a two-click operation is named after its tool", () => {
    const h = new History(parseMapDoc(office));
    const r = lineOp(h.doc, act("act.extend"), extend, 5, 15); // a corridor wall to the wall at x = 7000
    if (!r.ok) throw new Error(r.reason);
    h.run(r.value);
    expect(actionMessage("undone", h.undo(), wording("en"))).toBe("Undone: extend a line");
  });

  it("says when there is nothing to undo or redo", () => {
    const h = new History(parseMapDoc(office));
    expect(actionMessage("nothingToUndo", h.undo(), wording("en"))).toBe("Nothing to undo");
    expect(actionMessage("nothingToRedo", h.redo(), wording("de"))).toBe("Nichts zu wiederholen");
  });

  it("every kind the editor adds has its own words (no internal label shows)", () => {
    for (const kind of KINDS) {
      const a = addAction(kind);
      expect(a.key).not.toBe("act.addObject");
      expect([en[a.key], de[a.key]].every((s) => s.length > 0 && !s.includes("{"))).toBe(true);
    }
    expect(actionMessage("undone", addAction("blob"), wording("en"))).toBe("Undone: add a blob");
  });
});

describe("the roadmap editor's Undo and Redo name the action with its station", () => {
  it.each([
    ["en", "Undone: add station Dock", "Redone: add station Dock"],
    ["de", "Rückgängig gemacht: Station Dock hinzufügen", "Wiederholt: Station Dock hinzufügen"],
  ] as const)("in %s", (lang, undone, redone) => {
    const text = wording(lang);
    const h = new RoadmapHistory(parseRoadmapDoc(officeRm));
    expect(h.run(addStation("Dock", 1000, 2000, 90), act("act.addStation", { name: "Dock" }))).toBeNull();
    expect(actionMessage("undone", h.undo(), text)).toBe(undone);
    expect(actionMessage("redone", h.redo(), text)).toBe(redone);
  });
});

describe("the catalogs", () => {
  it("word every action and every action message in both languages", () => {
    const keys = Object.keys(en).filter(
      (k) => k.startsWith("act.") || /^edit\.(actionDone|undone|redone|nothing)/.test(k),
    );
    expect(keys.length).toBeGreaterThan(30);
    for (const k of keys as Key[]) {
      expect([k, de[k].length > 0 && de[k] !== en[k]]).toEqual([k, true]);
    }
  });
});
