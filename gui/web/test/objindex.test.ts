import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import { addObject, deleteObjects, History, moveObjects } from "../src/editor/commands";
import { snap, type Pt } from "../src/editor/geometry";
import { newMapDoc, parseMapDoc } from "../src/editor/mapdoc";
import { ObjectIndex } from "../src/editor/objindex";
import { objectsAt, polygonEdgeAt, vertexAt } from "../src/editor/shapes";
import type { MapObject } from "../src/scene/map";

function rng(seed: number): () => number {
  let s = seed;
  return () => (s = (s * 1103515245 + 12345) % 2147483648) / 2147483648;
}

/** A document of every shape the index must place: lines, circles, polygons (some huge), labels, far and empty. */
function randomDoc(n: number, rnd: () => number): History {
  const h = new History(newMapDoc());
  const objs: Array<Omit<MapObject, "id">> = [];
  for (let i = 0; i < n; i++) {
    const x = Math.round(rnd() * 60000),
      y = Math.round(rnd() * 40000),
      pick = rnd();
    if (pick < 0.55) {
      objs.push({
        kind: "line",
        layer: 0,
        points: [x, y, x + Math.round((rnd() - 0.5) * 6000), y + Math.round((rnd() - 0.5) * 6000)],
        attrs: {},
      });
    } else if (pick < 0.7) {
      objs.push({ kind: "circle", layer: 0, points: [x, y], r: Math.round(rnd() * 3000), attrs: {} });
    } else if (pick < 0.8) {
      const w = rnd() < 0.2 ? 900000 : 3000; // some span far more cells than the index keeps them in
      objs.push({ kind: "prohibit", layer: 0, points: [x, y, x + w, y, x + w / 2, y + w], attrs: {} });
    } else if (pick < 0.9) {
      objs.push({ kind: "hiddenlabel", layer: 0, points: [x, y], text: "t", attrs: { text: "t" } });
    } else if (pick < 0.95) {
      objs.push({ kind: "door", layer: 0, points: [], attrs: {} });
    } else {
      objs.push({ kind: "line", layer: 0, points: [1e13 + x, y, 1e13 + x + 10, y], attrs: {} });
    }
  }
  for (const o of objs) {
    h.run(addObject(h.doc, o));
  }
  return h;
}

function endpoints(objects: readonly MapObject[]): Pt[] {
  return objects.flatMap((o) =>
    Array.from({ length: Math.floor(o.points.length / 2) }, (_, k) => ({ x: o.points[2 * k], y: o.points[2 * k + 1] })),
  );
}

/** Every hit test on the objects the index gives equals the same test over the whole document. */
function expectSameAnswers(h: History, rnd: () => number, queries: number): void {
  const all = h.doc.scene.objects;
  for (let q = 0; q < queries; q++) {
    const pick = all[Math.floor(rnd() * all.length)];
    const onObject = pick !== undefined && pick.points.length >= 2 && rnd() < 0.6;
    const x = onObject ? pick.points[0] + (rnd() - 0.5) * 200 : rnd() * 70000 - 5000;
    const y = onObject ? pick.points[1] + (rnd() - 0.5) * 200 : rnd() * 50000 - 5000;
    const tol = [1, 80, 400, 3000, 5e6][Math.floor(rnd() * 5)];
    const near = h.near(x, y, tol);
    expect(objectsAt(near, x, y, tol)).toEqual(objectsAt(all, x, y, tol));
    expect(vertexAt(near, x, y, tol)).toEqual(vertexAt(all, x, y, tol));
    expect(polygonEdgeAt(near, x, y, tol)).toEqual(polygonEdgeAt(all, x, y, tol));
    expect(snap({ x, y }, endpoints(near), tol, 10)).toEqual(snap({ x, y }, endpoints(all), tol, 10));
  }
}

describe("the editor's spatial index", () => {
  it("gives the hit tests and the snap exactly the linear scan's answers", () => {
    const rnd = rng(11);
    const h = randomDoc(1000, rnd);
    expectSameAnswers(h, rnd, 300);
  }, 60_000);

  it("stays exact through moves, deletions, additions, undo and redo", () => {
    const rnd = rng(5);
    const h = randomDoc(600, rnd);
    h.index();
    for (let step = 0; step < 150; step++) {
      const objs = h.doc.scene.objects;
      const id = objs[Math.floor(rnd() * objs.length)].id;
      const what = rnd();
      if (what < 0.4) {
        h.run(moveObjects(h.doc, [id], Math.round((rnd() - 0.5) * 20000), Math.round((rnd() - 0.5) * 20000)));
      } else if (what < 0.55) {
        h.run(deleteObjects(h.doc, [id]));
      } else if (what < 0.7) {
        h.run(
          addObject(h.doc, {
            kind: "line",
            layer: 0,
            points: [rnd() * 60000, rnd() * 40000, rnd() * 60000, rnd() * 40000],
            attrs: {},
          }),
        );
      } else if (what < 0.9) {
        h.undo();
      } else {
        h.redo();
      }
      expectSameAnswers(h, rnd, 4);
    }
  }, 60_000);

  it("hands out the near objects of the office map in document order, and only near ones", () => {
    const h = new History(parseMapDoc(office));
    const near = h.near(0, 11200, 50);
    const all = h.doc.scene.objects;
    expect(near.map((o) => all.indexOf(o))).toEqual([...near.map((o) => all.indexOf(o))].sort((a, b) => a - b));
    expect(near.length).toBeGreaterThan(0);
    expect(near.length).toBeLessThan(all.length / 2);
  });

  it("says when a query covers too many cells to answer from the grid", () => {
    const idx = new ObjectIndex([{ id: 0, kind: "line", layer: 0, points: [0, 0, 10, 10], attrs: {} }]);
    expect(idx.near(5, 5, 1)).toHaveLength(1);
    expect(idx.near(5, 5, 1e9)).toBeNull();
    expect(idx.near(50000, 50000, 1)).toEqual([]);
  });
});

describe("History.byId", () => {
  it("finds each object as a pass over the document does, through edits, undo and redo", () => {
    const rnd = rng(21);
    const h = randomDoc(300, rnd);
    for (let step = 0; step < 120; step++) {
      const objs = h.doc.scene.objects;
      const id = objs[Math.floor(rnd() * objs.length)].id;
      const what = rnd();
      if (what < 0.4) {
        h.run(moveObjects(h.doc, [id], 10, -20));
      } else if (what < 0.55) {
        h.run(deleteObjects(h.doc, [id]));
      } else if (what < 0.7) {
        h.run(addObject(h.doc, { kind: "line", layer: 0, points: [1, 2, 3, 4], attrs: {} }));
      } else if (what < 0.9) {
        h.undo();
      } else {
        h.redo();
      }
      for (const probe of [id, id + 1, h.doc.nextId - 1, h.doc.nextId]) {
        expect(h.byId(probe)).toBe(h.doc.scene.objects.find((o) => o.id === probe));
      }
    }
    expect(h.byId(null)).toBeUndefined();
  });
});
