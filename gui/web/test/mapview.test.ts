// The map view's parts (issue 31): the layer cache's geometry and bookkeeping, the controller's drag, the renderer's
// reading of the platform's parameters, and the editors' topic. What needs a canvas or a worker is covered by the
// browser tests (tests/gui) and the benchmarks.
import { describe, expect, it } from "vitest";
import { covers, LayerCache, layerCamera, MARGIN, placement } from "../src/panels/map/layercache";
import { draggedPose, platformGeometry } from "../src/panels/map/platform";
import { nothingShown } from "../src/panels/map/shown";
import { type MapObject, type MapScene, sceneBounds } from "../src/scene/map";
import { Topic } from "../src/session/bus";
import type { EditedDocument } from "../src/session/edited";
import { toWorld } from "../src/view/camera";
import { footprint } from "../src/view/overlay";

const cam = { cx: 1000, cy: 2000, scale: 0.1, width: 800, height: 600 };
const line = (id: number, x: number, y = 0, kind = "line"): MapObject => ({
  id,
  kind,
  layer: 0,
  points: [x, y, x + 10, y + 5],
  attrs: {},
});

describe("the static layer's coverage", () => {
  const layer = { cam: layerCamera(cam), version: 3 };
  it("is a margin larger than the view, on the same centre and scale", () => {
    expect(layer.cam).toEqual({ ...cam, width: 800 + 2 * MARGIN, height: 600 + 2 * MARGIN });
    expect(covers(layer, cam, 3)).toBe(true);
  });
  it("covers a pan up to the margin, not beyond", () => {
    const within = { ...cam, cx: cam.cx + MARGIN / cam.scale, cy: cam.cy - MARGIN / cam.scale };
    const beyond = { ...cam, cx: cam.cx + (MARGIN + 1) / cam.scale };
    expect(covers(layer, within, 3)).toBe(true);
    expect(covers(layer, beyond, 3)).toBe(false);
  });
  it("is out of date after a zoom, a resize larger than it, or another version of the documents", () => {
    expect(covers(layer, { ...cam, scale: 0.2 }, 3)).toBe(false);
    expect(covers(layer, { ...cam, width: 801 }, 3)).toBe(false);
    expect(covers(layer, cam, 4)).toBe(false);
    expect(covers(null, cam, 3)).toBe(false);
  });
  it("is placed so that a world point lands where the current camera shows it", () => {
    const moved = { ...cam, cx: 1500, cy: 1800, scale: 0.2 };
    const { dx, dy, r } = placement(layer.cam, moved);
    expect(r).toBe(2);
    // the world point at pixel (100, 50) of the layer is drawn at dx + 100 r, dy + 50 r of the view
    const [wx, wy] = toWorld(layer.cam, 100, 50);
    const [vx, vy] = toWorld(moved, dx + 100 * r, dy + 50 * r);
    expect(vx).toBeCloseTo(wx, 6);
    expect(vy).toBeCloseTo(wy, 6);
    expect(placement(layer.cam, cam)).toEqual({ dx: -MARGIN, dy: -MARGIN, r: 1 });
  });
});

describe("the layer cache without a worker (node)", () => {
  const setUp = () => {
    const shown = nothingShown();
    const drawn: Array<Record<string, number>> = [];
    let frames = 0;
    const cache = new LayerCache({
      shown,
      cam: () => cam,
      layers: () => ({ grid: true, map: true, roadmap: true, labels: true, kinds: {} }),
      drawn: (c) => drawn.push(c),
      invalidate: () => frames++,
    });
    return { shown, cache, frames: () => frames };
  };
  it("bumps the version at every change of the documents or the options and asks for a frame", () => {
    const { shown, cache, frames } = setUp();
    expect(cache.version).toBe(0);
    shown.scene = { name: "m", version: null, objects: [line(1, 0), line(2, 100), line(3, 0, 0, "circle")] };
    shown.bounds = sceneBounds(shown.scene);
    cache.documentsChanged();
    expect(cache.version).toBe(1);
    expect(frames()).toBe(1);
    expect(cache.counts.line).toBe(2);
    cache.optionsChanged();
    expect(cache.version).toBe(2);
    expect(cache.drawnFor).toBeNull(); // nothing drawn yet: drawing is the renderer's frame
  });
  it("gives the bounds after an edit from the base without a pass over every object", () => {
    const { shown, cache } = setUp();
    const [a, b, inside] = [line(1, 0), line(2, 100), { ...line(3, 50), points: [50, 1, 60, 3] }];
    const scene: MapScene = { name: "m", version: null, objects: [a, b, inside] };
    shown.scene = scene;
    shown.bounds = sceneBounds(scene);
    cache.documentsChanged();
    // the editor replaces objects of the same scene: one inside is deleted, one outside added
    scene.objects = [a, b, line(4, 500, 70)];
    expect(cache.editedBounds(scene)).toEqual(sceneBounds(scene));
    // an extreme object deleted: the bounds must be computed
    scene.objects = [b, inside];
    expect(cache.editedBounds(scene)).toBeNull();
    // another scene is not an edit of the base
    expect(cache.editedBounds({ ...scene })).toBeNull();
  });
  it("hands out the layer times once", () => {
    const { cache } = setUp();
    expect(cache.takeTimes()).toEqual([]);
  });
});

describe("a drag of the shift or flag tool", () => {
  const start = { x: 400, y: 300, button: 0, cam, pose: { x: 1000, y: 2000, angle: 30 } };
  it("moves the pose by the world distance the pointer went (left button), keeping the angle", () => {
    expect(draggedPose(start, cam, 410, 280)).toEqual({ x: 1100, y: 2200, angle: 30 });
  });
  it("turns it toward the pointer (right button), to a tenth of a degree", () => {
    const right = { ...start, button: 2 };
    expect(draggedPose(right, cam, 400, 200)).toEqual({ x: 1000, y: 2000, angle: 90 });
    expect(draggedPose(right, cam, 300, 300).angle).toBe(180);
    expect(draggedPose(right, cam, 410, 290).angle).toBe(45);
  });
});

describe("the platform's geometry from its parameters", () => {
  it("falls back to the guide's defaults for what is missing or not a number", () => {
    const g = platformGeometry({ parameters: [{ key: "PltfLength", value: "x" }] as never });
    expect(g.footprint).toEqual(footprint(650, 430, 100));
    expect(g.usSensors).toHaveLength(16);
    expect(g.usSensors[0]).toEqual({ x: 0, y: 0, angle: 0 });
  });
  it("takes the footprint and the ultrasonic sensors' poses", () => {
    const parameters = [
      { key: "PltfLength", value: "800" },
      { key: "DistWheels", value: "500" },
      { key: "DistPltfCenterToWheelAxis", value: "50" },
      { key: "USSensor03PosX", value: "120" },
      { key: "USSensor03PosY", value: "-40" },
      { key: "USSensor03Angle", value: "-90" },
    ];
    const g = platformGeometry({ parameters } as never);
    expect(g.footprint).toEqual(footprint(800, 500, 50));
    expect(g.usSensors[2]).toEqual({ x: 120, y: -40, angle: -90 });
  });
});

describe("the editors' topic", () => {
  it("replays the open editor's document to a late subscriber, and the closing", () => {
    const edited = new Topic<EditedDocument | null>();
    const hooks = { down() {}, move() {}, up() {}, draw() {} };
    const scene: MapScene = { name: "m", version: null, objects: [] };
    edited.publish({ shows: "map", scene, hooks });
    const seen: Array<EditedDocument | null> = [];
    edited.subscribe((e) => seen.push(e));
    edited.publish(null);
    expect(seen).toEqual([{ shows: "map", scene, hooks }, null]);
  });
});
