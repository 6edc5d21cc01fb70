import { describe, expect, it } from "vitest";
import {
  changedWindow,
  dirtyPart,
  HeadTailBoxes,
  patchCounts,
  union,
  windowBox,
  windowSize,
} from "../src/view/scenediff";
import { toScreen } from "../src/view/camera";
import { applyPatch, lineParts, pack, preparePacked, type Prepared } from "../src/view/maprender";
import { countKinds, type MapObject, type MapScene, sceneBounds } from "../src/scene/map";

const line = (id: number, x: number, kind = "line"): MapObject => ({
  id,
  kind,
  layer: 0,
  points: [x, 0, x + 10, 5],
  attrs: {},
});
const area = (id: number, x: number): MapObject => ({
  id,
  kind: "prohibit",
  layer: 0,
  points: [x, 0, x + 5, 0, x, 5],
  attrs: {},
});

describe("changedWindow", () => {
  const a = line(0, 0),
    b = line(1, 10),
    c = line(2, 20),
    d = line(3, 30);
  it("is empty for the same list", () => {
    expect(changedWindow([a, b, c], [a, b, c])).toEqual({ start: 3, baseEnd: 3, curEnd: 3 });
    expect(windowSize(changedWindow([a, b, c], [a, b, c]))).toBe(0);
  });
  it("finds a replaced object", () => {
    expect(changedWindow([a, b, c], [a, d, c])).toEqual({ start: 1, baseEnd: 2, curEnd: 2 });
  });
  it("finds an insertion and a removal", () => {
    expect(changedWindow([a, c], [a, b, c])).toEqual({ start: 1, baseEnd: 1, curEnd: 2 });
    expect(changedWindow([a, b, c], [a, c])).toEqual({ start: 1, baseEnd: 2, curEnd: 1 });
    expect(changedWindow([a, b], [a, b, d])).toEqual({ start: 2, baseEnd: 2, curEnd: 3 });
    expect(changedWindow([a, b], [])).toEqual({ start: 0, baseEnd: 2, curEnd: 0 });
  });
  it("does not let head and tail overlap on repeats", () => {
    expect(changedWindow([a, a], [a, a, a])).toEqual({ start: 2, baseEnd: 2, curEnd: 3 });
  });
});

describe("patchCounts", () => {
  it("equals countKinds of the edited list", () => {
    const base = [line(0, 0), area(1, 10), line(2, 20, "auxline"), line(3, 30)];
    const cur = [base[0], area(4, 0), area(5, 1), base[3]];
    const w = changedWindow(base, cur);
    const scene = (objects: MapObject[]): MapScene => ({ name: "", version: null, objects });
    expect(patchCounts(countKinds(scene(base)), base, cur, w)).toEqual(countKinds(scene(cur)));
  });
});

/** Every segment a Prepared draws in a view, per kind, as sorted coordinate strings; and its others in order. */
function drawnSet(p: Prepared, view: { minX: number; minY: number; maxX: number; maxY: number }, whole: boolean) {
  const out: Record<string, string[]> = {};
  for (const kind of ["line", "auxline", "reflmark"]) {
    const segs: string[] = [];
    for (const part of lineParts(p, kind, view, whole)) {
      for (let j = 0; j < part.n; j++) {
        const s = part.idx === null ? j : part.idx[j];
        segs.push(Array.from(part.segs.subarray(4 * s, 4 * s + 4)).join(","));
      }
    }
    out[kind] = segs.sort();
  }
  return { lines: out, others: p.others.map((o) => o.id), bounds: p.bounds };
}

describe("applyPatch", () => {
  it("draws what a full rebuild of the edited scene draws, in every view", () => {
    let seed = 11;
    const rnd = () => (seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648;
    const kinds = ["line", "auxline", "reflmark"];
    const objects: MapObject[] = [];
    for (let i = 0; i < 400; i++) {
      const o = rnd() < 0.1 ? area(i, rnd() * 1000) : line(i, rnd() * 1000, kinds[Math.floor(rnd() * 3)]);
      o.points = o.points.map((v, k) => (k % 2 === 1 ? v + rnd() * 1000 : v));
      objects.push(o);
    }
    const scene: MapScene = { name: "", version: null, objects };
    const basePrep = preparePacked(pack(scene));
    const snapshot = objects.slice();
    for (let step = 0; step < 30; step++) {
      // an edit like the editor's: replace, insert or remove whole objects somewhere
      const at = Math.floor(rnd() * objects.length);
      const r = rnd();
      if (r < 0.4) {
        objects[at] = line(1000 + step, rnd() * 3000 - 1000, kinds[step % 3]);
      } else if (r < 0.7) {
        objects.splice(at, 0, step % 4 === 0 ? area(2000 + step, rnd() * 1000) : line(2000 + step, rnd() * 1000));
      } else {
        objects.splice(at, 1);
      }
      const w = changedWindow(snapshot, objects);
      const added = pack({ ...scene, objects: objects.slice(w.start, w.curEnd) });
      const patched = applyPatch(basePrep, {
        bounds: sceneBounds(scene),
        hideFrom: w.start,
        hideTo: w.baseEnd,
        added,
        addedCount: w.curEnd - w.start,
      });
      const full = preparePacked(pack(scene));
      for (const view of [
        { minX: 100, minY: 100, maxX: 400, maxY: 600 },
        { minX: -5000, minY: -5000, maxX: 5000, maxY: 5000 },
      ]) {
        expect(drawnSet(patched, view, false)).toEqual(drawnSet(full, view, false));
      }
      expect(drawnSet(patched, full.bounds!, true)).toEqual(drawnSet(full, full.bounds!, true));
    }
  });
});

describe("dirty regions", () => {
  it("boxes the objects a window touches, radius included", () => {
    const base = [line(0, 0), line(1, 100)];
    const circle: MapObject = { id: 2, kind: "circle", layer: 0, points: [500, 500], r: 50, attrs: {} };
    const cur = [base[0], circle];
    expect(windowBox(base, cur, changedWindow(base, cur))).toEqual({ minX: 100, minY: 0, maxX: 550, maxY: 550 });
    expect(windowBox(base, base, changedWindow(base, base))).toBeNull();
    expect(union(null, { minX: 0, minY: 0, maxX: 1, maxY: 1 })).toEqual({ minX: 0, minY: 0, maxX: 1, maxY: 1 });
  });
  it("maps a world box to whole layer pixels and a camera that draws them at the same place", () => {
    const cam = { cx: 1000, cy: 2000, scale: 0.1, width: 800, height: 600 };
    const part = dirtyPart(cam, { minX: 1000, minY: 2000, maxX: 1500, maxY: 2300 }, 10)!;
    expect(part.x).toBe(390);
    expect(part.y).toBe(260);
    expect([part.cam.width, part.cam.height]).toEqual([70, 50]);
    for (const [x, y] of [
      [1000, 2000],
      [1500, 2300],
      [1234, 2111],
    ]) {
      const [lx, ly] = toScreen(cam, x, y);
      const [px, py] = toScreen(part.cam, x, y);
      expect(px + part.x).toBeCloseTo(lx, 6);
      expect(py + part.y).toBeCloseTo(ly, 6);
    }
    expect(dirtyPart(cam, { minX: 99999, minY: 0, maxX: 100000, maxY: 1 }, 10)).toBeNull();
  });
});

describe("HeadTailBoxes", () => {
  it("gives the box of the objects outside any window exactly as sceneBounds computes it", () => {
    let seed = 9;
    const rnd = (): number => (seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648;
    const objects: MapObject[] = [];
    for (let i = 0; i < 300; i++) {
      const pts = Array.from({ length: 2 * Math.floor(rnd() * 4) }, () => Math.round((rnd() - 0.5) * 1e5));
      const o: MapObject = { id: i, kind: "line", layer: 0, points: pts, attrs: {} };
      if (rnd() < 0.2) {
        o.r = Math.round((rnd() - 0.1) * 5000); // a few negative: the box inside out, as sceneBounds has it
      }
      objects.push(o);
    }
    const boxes = new HeadTailBoxes(objects);
    for (let q = 0; q < 500; q++) {
      const a = Math.floor(rnd() * 301);
      const b = a + Math.floor(rnd() * (301 - a));
      const outside = [...objects.slice(0, a), ...objects.slice(b)];
      expect(boxes.outside(a, b)).toEqual(sceneBounds({ name: "", version: null, objects: outside }));
    }
    expect(boxes.outside(0, 300)).toBeNull();
  });
});
