/**
 * The map view's static layer (grid, map, roadmap): drawn by a worker (view/layerworker.ts) into a bitmap a margin
 * larger than the view, kept with the camera it was drawn for and the documents' version. A frame draws the last
 * layer moved and scaled to the current camera; a new one is asked for when the view has left the old one or its
 * scale changed (one request in flight at a time). Without workers the layer is drawn on the page.
 *
 * Rules: the documents come from `Shown` and are never changed here. An edit of the shown scene (the editor
 * changes its document's object list by whole objects) goes to the worker as a patch of its base, and its region
 * is redrawn on the page at once into a small canvas laid over the layer (issue 20); the worker's layer of the
 * same version follows and replaces both. Every change of what the layer shows bumps `version`.
 */
import type { Bounds, MapScene } from "../../scene/map";
import type { Camera } from "../../view/camera";
import type { PlacedLabel } from "../../view/labels";
import {
  applyPatch,
  buildGrids,
  copyPacked,
  drawStatic,
  type Layers,
  pack,
  prepare,
  preparePacked,
  type Prepared,
  type ScenePatch,
  transfers,
} from "../../view/maprender";
import {
  type Box,
  changedWindow,
  dirtyPart,
  HeadTailBoxes,
  patchCounts,
  union,
  windowBox,
  windowSize,
} from "../../view/scenediff";
import type { Shown } from "./shown";

/** px of static layer beyond each edge of the view */
export const MARGIN = 256;
/** patches kept over one layer image before they are flattened into a copy of it */
const PATCHES_MAX = 16;
/** an edit touching at most this many objects goes to the worker as a patch of its base (issue 20) */
const PATCH_MAX = 2000;
/** px around an edit's box redrawn on the page: the front-side ticks (6 px), the widest stroke (4 px) */
const DIRTY_PAD = 10;
/** ms after the worker's first layer of a new base before the page builds its own index of it (for edits) */
const PAGE_INDEX_DELAY_MS = 300;
/** layer times kept (the oldest half is dropped beyond) */
const TIMES_MAX = 1000;

/** A region of the static layer an edit redrew on the page: its image and where it goes (CSS px of the layer). */
interface LayerPatch {
  image: HTMLCanvasElement;
  x: number;
  y: number;
  width: number;
  height: number;
}

/**
 * A static layer: its image, the camera it was drawn for (margin included), the document version, and the regions
 * edits redrew on the page over the image since (drawn on top, in order; issue 20).
 */
interface Layer {
  image: CanvasImageSource;
  cam: Camera;
  version: number;
  patches?: LayerPatch[];
}

/** The scene the worker holds as its base (its objects as they were then) and their counts per kind. */
interface Base {
  scene: MapScene;
  objects: MapScene["objects"];
  counts: Record<string, number>;
  bounds: Bounds | null;
  /** the boxes of the base's heads and tails (built with the page's grids): exact bounds after any edit */
  boxes?: HeadTailBoxes;
  /** the page's grids and boxes are asked for */
  indexing?: boolean;
}

/** What the cache asks of the view: the camera, the layers the options show, and where its results go. */
export interface LayerHost {
  readonly shown: Shown;
  cam(): Camera;
  layers(): Layers;
  /** what a new layer drew per kind (margin included), and the boxes of its texts (layer px) */
  drawn(counts: Record<string, number>, labels: readonly PlacedLabel[]): void;
  invalidate(): void;
}

/** Does `l` show the view of camera `c` at its own scale, margin included, for document version `version`? */
export function covers(l: { cam: Camera; version: number } | null, c: Camera, version: number): boolean {
  if (l === null || l.version !== version || l.cam.scale !== c.scale) {
    return false;
  }
  return (
    Math.abs((c.cx - l.cam.cx) * c.scale) <= MARGIN &&
    Math.abs((c.cy - l.cam.cy) * c.scale) <= MARGIN &&
    l.cam.width >= c.width + 2 * MARGIN &&
    l.cam.height >= c.height + 2 * MARGIN
  );
}

/** The camera of a layer for the view of `c`: the same centre and scale, a margin larger. */
export function layerCamera(c: Camera): Camera {
  return { ...c, width: c.width + 2 * MARGIN, height: c.height + 2 * MARGIN };
}

/** Where the layer drawn for `l` lies on a canvas of camera `c`: offset and scale. */
export function placement(l: Camera, c: Camera): { dx: number; dy: number; r: number } {
  const r = c.scale / l.scale;
  return {
    dx: c.width / 2 - (l.width / 2) * r + (l.cx - c.cx) * c.scale,
    dy: c.height / 2 - (l.height / 2) * r + (c.cy - l.cy) * c.scale,
    r,
  };
}

function keep(times: number[], ms: number): void {
  times.push(ms);
  if (times.length > TIMES_MAX) {
    times.splice(0, TIMES_MAX / 2);
  }
}

export class LayerCache {
  private layer: Layer | null = null;
  private docVersion = 0;
  private worker: Worker | null = null;
  private base: Base | null = null;
  /** the current scene's counts per kind */
  private kindCounts: Record<string, number> = {};
  /** the scene's index for drawing on the page (built only without a worker, or for the benchmark's baseline) */
  private prepared: Prepared | null = null;
  /** the page's index of the base (built once, a while after the base is drawn): an edit is redrawn here at once */
  private pageBase: { of: MapScene["objects"]; prep: Prepared } | null = null;
  /** the world box of the objects the current patch touches (they differ from the base there) */
  private patchBox: Box | null = null;
  /** the layer was drawn on the page for an edit: the worker's layer of the version is still to come */
  private countsStale = false;
  private inFlight: { id: number; version: number } | null = null;
  private requestId = 0;
  /** ms the layer worker (or the page) took for its last layers */
  private times: number[] = [];
  /** draw the static layer on the page in every frame (the benchmark's baseline) */
  private sync = false;

  constructor(private readonly host: LayerHost) {
    this.startWorker();
  }

  /** the documents' version: bumped by every change of what the static layer shows */
  get version(): number {
    return this.docVersion;
  }

  /** the current scene's objects per kind */
  get counts(): Readonly<Record<string, number>> {
    return this.kindCounts;
  }

  /** the version and camera of the last layer (null before the first) */
  get drawnFor(): { readonly version: number; readonly cam: Camera } | null {
    const l = this.layer;
    return l === null ? null : { version: l.version, cam: l.cam };
  }

  /** Does the last layer show the current view? */
  get current(): boolean {
    return covers(this.layer, this.host.cam(), this.docVersion);
  }

  /** The view options changed: every layer drawn so far is out of date. */
  optionsChanged(): void {
    this.docVersion++;
  }

  /** The baseline of the benchmark: draw the static layer on the page in every frame (true) or by the worker. */
  setSync(on: boolean): void {
    this.sync = on;
  }

  /** The ms of the layers drawn since the last call. */
  takeTimes(): number[] {
    return this.times.splice(0);
  }

  /** The shown scene was replaced or edited (not only the roadmap): the page's index of it is out of date. */
  sceneReplaced(): void {
    this.prepared = null;
  }

  /**
   * The bounds of the base scene after an edit without a pass over every object (issue 20): the box of the base's
   * objects outside the changed window (head and tail boxes) and of the new ones; before those boxes are built,
   * the base's bounds grown by the new objects' box, exact when the objects gone lay strictly inside them (an
   * extreme point is then still held by an object kept). Null when neither holds: compute them.
   */
  editedBounds(scene: MapScene): Bounds | null {
    const b = this.base;
    if (b === null || b.scene !== scene || b.bounds === null) {
      return null;
    }
    const w = changedWindow(b.objects, scene.objects);
    const added = windowBox(b.objects, scene.objects, { ...w, baseEnd: w.start });
    if (b.boxes !== undefined) {
      return union(b.boxes.outside(w.start, w.baseEnd), added);
    }
    const gone = windowBox(b.objects, scene.objects, { ...w, curEnd: w.start });
    const bb = b.bounds;
    if (gone !== null && !(gone.minX > bb.minX && gone.minY > bb.minY && gone.maxX < bb.maxX && gone.maxY < bb.maxY)) {
      return null;
    }
    return union(bb, added);
  }

  /** The shown documents changed: a patch of the base when the same scene was edited, else the whole scene. */
  documentsChanged(): void {
    this.docVersion++;
    if (!this.sendPatch()) {
      this.sendScene();
    }
    this.host.invalidate();
  }

  private sendScene(): void {
    const { scene: s, bounds, roadmap } = this.host.shown;
    const packed = s === null ? null : pack(s, bounds); // one pass: segments, counts per kind (bounds known)
    this.kindCounts = packed === null ? {} : packed.kinds;
    this.base = s === null ? null : { scene: s, objects: s.objects.slice(), counts: this.kindCounts, bounds };
    // while the editor shows its document the page keeps a copy of the packed arrays (its own index of the base,
    // grids built later): an edit is drawn on the page from the first one on (issue 20)
    const editing = this.host.shown.hooks !== null;
    const kept = packed !== null && this.worker !== null && editing ? copyPacked(packed) : null;
    this.pageBase = kept === null || this.base === null ? null : { of: this.base.objects, prep: preparePacked(kept) };
    this.patchBox = null;
    this.worker?.postMessage({ type: "scene", scene: packed, roadmap }, packed === null ? [] : transfers(packed));
  }

  /**
   * The same scene edited: only the objects in the changed window go to the worker, which draws them over its
   * base. False when a whole scene must go.
   */
  private sendPatch(): boolean {
    const { scene: s, bounds, roadmap } = this.host.shown;
    const b = this.base;
    if (this.worker === null || s === null || b === null || b.scene !== s) {
      return false;
    }
    const w = changedWindow(b.objects, s.objects);
    if (windowSize(w) > PATCH_MAX) {
      return false;
    }
    this.kindCounts = patchCounts(b.counts, b.objects, s.objects, w);
    const added = pack({ ...s, objects: s.objects.slice(w.start, w.curEnd) });
    const patch: ScenePatch = { bounds, hideFrom: w.start, hideTo: w.baseEnd, added, addedCount: w.curEnd - w.start };
    const box = windowBox(b.objects, s.objects, w);
    this.patchLayer(patch, union(box, this.patchBox));
    this.patchBox = box;
    this.worker.postMessage({ type: "patch", patch, roadmap }, transfers(added));
    this.askWorker(); // asked now, not at the next frame
    return true;
  }

  /**
   * An edit drawn on the page at once (issue 20): when the last layer shows the document just before the edit, the
   * region the edit touches (`dirty`, world) is redrawn from the page's index of the base and the patch into a
   * small canvas laid over the layer (the layer's image itself is neither copied nor redrawn). The worker's layer
   * of the same version follows and replaces both (same pixels, and the counts).
   */
  private patchLayer(patch: ScenePatch, dirty: Box | null): void {
    const l = this.layer;
    const pb = this.pageBase;
    if (l === null || pb === null || pb.of !== this.base?.objects || l.version !== this.docVersion - 1) {
      return;
    }
    const patches = [...(l.patches ?? [])];
    const part = dirty === null ? null : dirtyPart(l.cam, dirty, DIRTY_PAD);
    if (part !== null) {
      const dpr = window.devicePixelRatio || 1;
      const image = document.createElement("canvas");
      image.width = Math.max(1, Math.round(part.cam.width * dpr));
      image.height = Math.max(1, Math.round(part.cam.height * dpr));
      const ctx = image.getContext("2d")!;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      drawStatic(ctx, part.cam, applyPatch(pb.prep, patch), this.host.shown.roadmap, this.host.layers());
      patches.push({ image, x: part.x, y: part.y, width: part.cam.width, height: part.cam.height });
    }
    this.layer =
      patches.length > PATCHES_MAX
        ? this.flatten(l, patches)
        : { image: l.image, cam: l.cam, version: this.docVersion, patches };
    this.countsStale = true; // what is in view per kind: the worker's layer of this version says
  }

  /** One image of a layer and its patches (when edits came faster than the worker's layers for long). */
  private flatten(l: Layer, patches: readonly LayerPatch[]): Layer {
    const dpr = window.devicePixelRatio || 1;
    const canvas = document.createElement("canvas");
    canvas.width = Math.max(1, Math.round(l.cam.width * dpr));
    canvas.height = Math.max(1, Math.round(l.cam.height * dpr));
    const ctx = canvas.getContext("2d")!;
    ctx.drawImage(l.image, 0, 0);
    for (const p of patches) {
      ctx.drawImage(p.image, p.x * dpr, p.y * dpr);
    }
    if (l.image instanceof ImageBitmap) {
      l.image.close();
    }
    return { image: canvas, cam: l.cam, version: this.docVersion };
  }

  /** Ask the worker for a layer of the current version and view, unless one is being drawn. */
  private askWorker(): void {
    if (this.worker !== null && !this.sync && this.inFlight === null) {
      this.inFlight = { id: ++this.requestId, version: this.docVersion };
      const dpr = window.devicePixelRatio || 1;
      this.worker.postMessage({
        type: "render",
        id: this.requestId,
        cam: layerCamera(this.host.cam()),
        layers: this.host.layers(),
        dpr,
      });
    }
  }

  /**
   * The page's grids of the base and its head and tail boxes, built a while after the worker has drawn it (off the
   * load's critical path), and only while the editor shows its document (the platform's map is not edited). An
   * edit before then builds the grids it needs as it draws.
   */
  private buildPageBase(): void {
    const b = this.base;
    if (this.worker === null || b === null || this.host.shown.hooks === null || b.indexing === true) {
      return;
    }
    b.indexing = true;
    setTimeout(() => {
      if (this.base !== b) {
        return;
      }
      if (this.pageBase?.of !== b.objects) {
        this.pageBase = { of: b.objects, prep: prepare({ ...b.scene, objects: b.objects }) };
      }
      buildGrids(this.pageBase.prep); // here, not at the first edit
      b.boxes = new HeadTailBoxes(b.objects);
    }, PAGE_INDEX_DELAY_MS);
  }

  private startWorker(): void {
    if (typeof Worker === "undefined" || typeof OffscreenCanvas === "undefined") {
      return;
    }
    try {
      this.worker = new Worker(new URL("../../view/layerworker.ts", import.meta.url), { type: "module" });
    } catch {
      this.worker = null;
      return;
    }
    this.worker.onmessage = (e: MessageEvent) => {
      this.received(e.data as Parameters<LayerCache["received"]>[0]);
    };
    this.worker.onerror = () => {
      this.worker = null; // drawn on the page from now on
      this.inFlight = null;
      this.host.invalidate();
    };
  }

  private received(m: {
    id: number;
    cam: Camera;
    bitmap: ImageBitmap;
    drawn: Record<string, number>;
    labels: PlacedLabel[];
    ms: number;
  }): void {
    const asked = this.inFlight;
    this.inFlight = null;
    if (asked === null || asked.id !== m.id || (this.layer !== null && asked.version < this.layer.version)) {
      m.bitmap.close(); // not asked for, or older than the layer drawn on the page for an edit
      this.host.invalidate();
      return;
    }
    if (this.layer?.image instanceof ImageBitmap) {
      this.layer.image.close();
    }
    this.layer = { image: m.bitmap, cam: m.cam, version: asked.version };
    this.countsStale = this.countsStale && asked.version !== this.docVersion;
    keep(this.times, m.ms);
    this.host.drawn(m.drawn, m.labels);
    this.buildPageBase();
    this.host.invalidate();
  }

  /** Keep the static layer up to date for this frame: ask the worker (or draw here) when the view has left it. */
  update(): void {
    if (this.sync) {
      this.layer = null;
    }
    if (this.current && !this.countsStale) {
      return;
    }
    if (this.worker !== null && !this.sync) {
      this.askWorker();
      return;
    }
    const { scene, roadmap } = this.host.shown;
    if (this.prepared === null && scene !== null) {
      this.prepared = prepare(scene);
    }
    const dpr = window.devicePixelRatio || 1;
    const big = layerCamera(this.host.cam());
    const canvas = this.layer?.image instanceof HTMLCanvasElement ? this.layer.image : document.createElement("canvas");
    canvas.width = Math.round(big.width * dpr);
    canvas.height = Math.round(big.height * dpr);
    const ctx = canvas.getContext("2d")!;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const t0 = performance.now();
    const labels: PlacedLabel[] = [];
    const drawn = drawStatic(ctx, big, this.prepared, roadmap, this.host.layers(), labels);
    this.times.push(performance.now() - t0);
    this.layer = { image: canvas, cam: big, version: this.docVersion };
    this.host.drawn(drawn, labels);
  }

  /** The last layer, moved and scaled to the current camera, on a white ground. */
  draw(ctx: CanvasRenderingContext2D): void {
    const l = this.layer;
    const c = this.host.cam();
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, c.width, c.height);
    if (l === null) {
      return;
    }
    const { dx, dy, r } = placement(l.cam, c);
    ctx.imageSmoothingEnabled = false; // a scaled layer is a stand-in until the worker sends the new one
    ctx.drawImage(l.image, dx, dy, l.cam.width * r, l.cam.height * r);
    for (const p of l.patches ?? []) {
      ctx.drawImage(p.image, dx + p.x * r, dy + p.y * r, p.width * r, p.height * r);
    }
    ctx.imageSmoothingEnabled = true;
  }
}
