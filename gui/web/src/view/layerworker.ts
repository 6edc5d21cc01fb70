/**
 * The map view's layer worker: draws the static layer (grid, map, roadmap) on an OffscreenCanvas off the page's
 * thread and sends it back as an ImageBitmap. The page keeps drawing frames from the last layer (moved and scaled)
 * while a new one is drawn, so a frame's cost does not grow with the map's size.
 *
 * Messages in: {type: "scene", scene, roadmap} (the scene packed by maprender.ts `pack`, its arrays transferred;
 * the worker builds its own index) and
 * {type: "render", id, cam, layers, dpr}. Out: {type: "layer", id, cam, bitmap, drawn, ms}.
 */
import type { Roadmap } from "../scene/roadmap";
import type { Camera } from "./camera";
import { drawStatic, type Layers, type PackedScene, preparePacked, type Prepared } from "./maprender";

interface Scope {
  onmessage: ((e: MessageEvent) => void) | null;
  postMessage(message: unknown, transfer: Transferable[]): void;
}

const scope = self as unknown as Scope;
let prepared: Prepared | null = null;
let roadmap: Roadmap | null = null;

scope.onmessage = (e: MessageEvent) => {
  const m = e.data as
    | { type: "scene"; scene: PackedScene | null; roadmap: Roadmap | null }
    | { type: "render"; id: number; cam: Camera; layers: Layers; dpr: number };
  if (m.type === "scene") {
    prepared = m.scene === null ? null : preparePacked(m.scene);
    roadmap = m.roadmap;
    return;
  }
  const t0 = performance.now();
  const canvas = new OffscreenCanvas(Math.max(1, Math.round(m.cam.width * m.dpr)), Math.max(1, Math.round(m.cam.height * m.dpr)));
  const ctx = canvas.getContext("2d")!;
  ctx.setTransform(m.dpr, 0, 0, m.dpr, 0, 0);
  const drawn = drawStatic(ctx, m.cam, prepared, roadmap, m.layers);
  const bitmap = canvas.transferToImageBitmap();
  scope.postMessage({ type: "layer", id: m.id, cam: m.cam, bitmap, drawn, ms: performance.now() - t0 }, [bitmap]);
};
