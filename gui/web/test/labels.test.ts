import { describe, expect, it } from "vitest";
import office from "../../../fixtures/maps/office.map?raw";
import officeRm from "../../../fixtures/roadmaps/office.rm?raw";
import { parseMapDoc } from "../src/editor/mapdoc";
import { parseRoadmapDoc } from "../src/editor/roadmapdoc";
import type { Roadmap } from "../src/scene/roadmap";
import { fit } from "../src/view/camera";
import {
  BoxGrid,
  type Box,
  CANDIDATES,
  type LabelIn,
  labelAt,
  overlaps,
  type PlacedLabel,
  placeLabels,
} from "../src/view/labels";
import { type Ctx2D, drawStatic, type Layers, prepare } from "../src/view/maprender";
import { sceneBounds } from "../src/scene/map";

const station = (text: string, ax: number, ay: number, w = 60): LabelIn => ({
  kind: "station",
  text,
  ax,
  ay,
  w,
  size: 11,
});
const room = (text: string, ax: number, ay: number, w = 40): LabelIn => ({
  kind: "hiddenlabel",
  text,
  ax,
  ay,
  w,
  size: 12,
});

function pairsOverlapping(boxes: readonly Box[]): number {
  let n = 0;
  for (let i = 0; i < boxes.length; i++) {
    for (let j = i + 1; j < boxes.length; j++) {
      n += overlaps(boxes[i], boxes[j]) ? 1 : 0;
    }
  }
  return n;
}

/** The same greedy placement without a grid: every placed box checked (what the grid must agree with). */
function bruteForce(labels: readonly LabelIn[], obstacles: readonly Box[], width: number, height: number) {
  const taken: Box[] = [...obstacles];
  const placed: PlacedLabel[] = [];
  const rank = (l: LabelIn) => (l.kind === "station" ? 0 : 1);
  const order = labels.map((_, i) => i).sort((a, b) => rank(labels[a]) - rank(labels[b]) || a - b);
  for (const i of order) {
    const boxes = CANDIDATES[labels[i].kind]
      .map((c) => labelAt(labels[i], c))
      .filter((b) => b.x + b.w > 0 && b.y + b.h > 0 && b.x < width && b.y < height);
    const free = boxes.find((b) => !taken.some((t) => overlaps(t, b)));
    if (free !== undefined) {
      taken.push(free);
      placed.push(free);
    }
  }
  return placed;
}

describe("placeLabels", () => {
  it("keeps a lone station's name where it always was: up and right of the symbol", () => {
    const { placed, hidden } = placeLabels([station("A", 100, 100)], [], 800, 600);
    expect(hidden).toBe(0);
    expect(placed).toHaveLength(1);
    expect(placed[0].x).toBeGreaterThan(100);
    expect(placed[0].y + placed[0].h).toBeLessThan(100);
  });

  it("moves the second of two colliding stations to its next free corner (Corridor_02 and Corridor_03)", () => {
    const { placed, hidden } = placeLabels(
      [station("Corridor_02", 100, 100), station("Corridor_03", 142, 100)],
      [],
      800,
      600,
    );
    expect(hidden).toBe(0);
    expect(pairsOverlapping(placed)).toBe(0);
    expect(placed[0].y + placed[0].h).toBeLessThan(100); // the first keeps its place
    expect(placed[1].y).toBeGreaterThan(100); // the second goes below its symbol
  });

  it("places stations before map labels whatever their order, and leaves the station where it always was", () => {
    const labels = [room("Lobby", 105, 95), station("Corridor_W", 100, 100)];
    const { placed } = placeLabels(labels, [], 800, 600);
    const s = placed.find((l) => l.kind === "station")!;
    expect(s).toEqual(labelAt(labels[1], CANDIDATES.station[0]));
    expect(pairsOverlapping(placed)).toBe(0);
  });

  it("hides what finds no free place, and never overlaps: twenty names on one point", () => {
    const labels = Array.from({ length: 20 }, (_, i) => station(`S${i}`, 300, 300));
    const { placed, hidden } = placeLabels(labels, [], 800, 600);
    expect(placed.length + hidden).toBe(20);
    expect(hidden).toBeGreaterThan(0);
    expect(placed.length).toBeLessThanOrEqual(CANDIDATES.station.length);
    expect(pairsOverlapping(placed)).toBe(0);
  });

  it("leaves the obstacles (station symbols) free", () => {
    const symbol = { x: 100, y: 80, w: 12, h: 12 };
    const { placed } = placeLabels([room("Kitchen", 90, 90)], [symbol], 800, 600);
    expect(placed).toHaveLength(1);
    expect(overlaps(placed[0], symbol)).toBe(false);
  });

  it("leaves out a label all of whose places lie off the canvas (neither drawn nor hidden)", () => {
    expect(placeLabels([station("far", -500, -500)], [], 800, 600)).toEqual({ placed: [], hidden: 0 });
  });

  it("agrees with a placement without a grid on 3,000 random labels, and none of them overlap", () => {
    let seed = 7;
    const rnd = () => {
      seed = (seed * 1103515245 + 12345) % 2147483648;
      return seed / 2147483648;
    };
    const labels: LabelIn[] = Array.from({ length: 3000 }, (_, i) =>
      (i % 3 === 0 ? station : room)(`L${i}`, rnd() * 1600 - 100, rnd() * 1000 - 100, 10 + rnd() * 120),
    );
    const obstacles = labels
      .filter((l) => l.kind === "station")
      .map((l) => ({ x: l.ax - 6, y: l.ay - 6, w: 12, h: 12 }));
    const { placed, hidden } = placeLabels(labels, obstacles, 1400, 800);
    expect(placed).toEqual(bruteForce(labels, obstacles, 1400, 800));
    expect(pairsOverlapping(placed)).toBe(0);
    expect(hidden).toBeGreaterThan(0);
  });
});

describe("BoxGrid", () => {
  it("finds a box across cells and at negative coordinates, and not one that only touches", () => {
    const g = new BoxGrid(10);
    g.add({ x: -25, y: -25, w: 40, h: 5 });
    expect(g.hits({ x: 10, y: -22, w: 3, h: 3 })).toBe(true);
    expect(g.hits({ x: 15, y: -22, w: 3, h: 3 })).toBe(false); // touches the right edge
    expect(g.hits({ x: -100, y: -100, w: 3, h: 3 })).toBe(false);
  });
});

/** A Canvas2D that draws nothing and measures a text as 0.6 of its font size per character. */
function fakeCtx(): Ctx2D {
  let size = 10;
  const target = {
    canvas: { width: 0, height: 0 },
    set font(f: string) {
      size = Number.parseFloat(f);
    },
    get font() {
      return `${size}px sans-serif`;
    },
    measureText: (s: string) => ({ width: 0.6 * size * s.length }),
  };
  return new Proxy(target, {
    get: (o, k) => (k in o ? (o as Record<string | symbol, unknown>)[k] : () => undefined),
    set: (o, k, v) => {
      (o as Record<string | symbol, unknown>)[k] = v;
      return true;
    },
  }) as unknown as Ctx2D;
}

const ALL: Layers = {
  grid: false,
  map: true,
  roadmap: true,
  labels: true,
  kinds: new Proxy({}, { get: () => true }) as Record<string, boolean>,
};

describe("drawStatic's labels on the office map", () => {
  const scene = parseMapDoc(office).scene;
  const { stations, edges } = parseRoadmapDoc(officeRm);
  const roadmap = { name: "office.rm", stations, edges } as unknown as Roadmap;
  const prep = prepare(scene);
  const whole = fit({ cx: 0, cy: 0, scale: 1, width: 1100, height: 700 }, sceneBounds(scene)!);

  for (const [name, factor] of [
    ["the whole map", 1],
    ["zoomed out twice", 1 / 2.25],
    ["zoomed in", 3],
  ] as const) {
    it(`draws every text at most once and none over another: ${name}`, () => {
      const cam = { ...whole, scale: whole.scale * factor };
      const out: PlacedLabel[] = [];
      const drawn = drawStatic(fakeCtx(), cam, prep, roadmap, ALL, out);
      expect(pairsOverlapping(out)).toBe(0);
      expect(drawn.labels).toBe(out.length);
      // every text is in reach when the map is in view; zoomed in, those far off the canvas are left out
      const all = roadmap.stations.length + 10; // 18 stations, 10 room names
      expect(drawn.labels + drawn.labelsHidden)[factor <= 1 ? "toBe" : "toBeLessThan"](all); // 18 stations, 10 room names
      expect(new Set(out.map((l) => `${l.kind}:${l.text}`)).size).toBe(out.length);
    });
  }

  it("draws every station's name on the whole office map (none hidden at the default zoom)", () => {
    const out: PlacedLabel[] = [];
    drawStatic(fakeCtx(), whole, prep, roadmap, ALL, out);
    expect(
      out
        .filter((l) => l.kind === "station")
        .map((l) => l.text)
        .sort(),
    ).toEqual(roadmap.stations.map((s) => s.name).sort());
  });
});
