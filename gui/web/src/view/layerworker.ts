/**
 * The map view's layer worker: draws the static layer (grid, map, roadmap) on an OffscreenCanvas off the page's
 * thread and sends it back as an ImageBitmap. The page keeps drawing frames from the last layer (moved and scaled)
 * while a new one is drawn, so a frame's cost does not grow with the map's size.
 *
 * Messages in: {type: "scene", scene, roadmap} (the scene packed by maprender.ts `pack`, its arrays transferred;
 * the worker builds its own index: the base), {type: "patch", patch, roadmap} (an edit of the base: only the
 * changed objects, drawn over the base's index, which is not rebuilt; issue 20) and
 * {type: "render", id, cam, layers, dpr}. Out: {type: "layer", id, cam, bitmap, drawn, labels, ms} (`labels`: the
 * boxes of the texts drawn, layer px; view/labels.ts).
 */
import type { Roadmap } from "../scene/roadmap";
import type { Camera } from "./camera";
import type { PlacedLabel } from "./labels";
import {
  applyPatch,
  buildGrids,
  drawStatic,
  type Layers,
  type PackedScene,
  preparePacked,
  type Prepared,
  type ScenePatch,
} from "./maprender";

interface Scope {
  onmessage: ((e: MessageEvent) => void) | null;
  postMessage(message: unknown, transfer: Transferable[]): void;
}

const scope = self as unknown as Scope;
let base: Prepared | null = null;
let prepared: Prepared | null = null;
let roadmap: Roadmap | null = null;

let kept: OffscreenCanvasRenderingContext2D | null = null;

/**
 * One canvas and context for every layer, copied into the bitmap sent: a new OffscreenCanvas per layer, or the new
 * backing store transferToImageBitmap leaves, cost 15-40 ms of the worker's time per layer in headless chromium
 * under load (issue 20); the copy 10-30 ms.
 */
function surface(width: number, height: number): OffscreenCanvasRenderingContext2D {
  if (kept === null || kept.canvas.width !== width || kept.canvas.height !== height) {
    kept = new OffscreenCanvas(width, height).getContext("2d")!;
  }
  kept.setTransform(1, 0, 0, 1, 0, 0);
  return kept;
}

scope.onmessage = (e: MessageEvent) => {
  const m = e.data as
    | { type: "scene"; scene: PackedScene | null; roadmap: Roadmap | null }
    | { type: "patch"; patch: ScenePatch; roadmap: Roadmap | null }
    | { type: "render"; id: number; cam: Camera; layers: Layers; dpr: number };
  if (m.type === "scene") {
    base = m.scene === null ? null : preparePacked(m.scene);
    prepared = base;
    roadmap = m.roadmap;
    return;
  }
  if (m.type === "patch") {
    prepared = base === null ? null : applyPatch(base, m.patch);
    roadmap = m.roadmap;
    return;
  }
  const t0 = performance.now();
  const ctx = surface(Math.max(1, Math.round(m.cam.width * m.dpr)), Math.max(1, Math.round(m.cam.height * m.dpr)));
  ctx.setTransform(m.dpr, 0, 0, m.dpr, 0, 0);
  const labels: PlacedLabel[] = [];
  const drawn = drawStatic(ctx, m.cam, prepared, roadmap, m.layers, labels);
  // a copy of the kept canvas (one render is in flight at a time, so the canvas is not drawn again before this)
  void createImageBitmap(ctx.canvas).then((bitmap) => {
    scope.postMessage({ type: "layer", id: m.id, cam: m.cam, bitmap, drawn, labels, ms: performance.now() - t0 }, [
      bitmap,
    ]);
    // the base's grids are built after its first layer is sent (a view of the whole map needs none; issue 20)
    setTimeout(() => base !== null && buildGrids(base), 0);
  });
};
