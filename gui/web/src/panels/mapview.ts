/**
 * The map view and its tools (guide 5.3): refresh, zoom all, zoom in/out, zoom to a selected area, pan, shift
 * the platform (CMD_SET_FRM_PLTF), the target flag (CMD_MOVE_ABS in Automatic) and the target station
 * (CMD_MOVE_TO_STATION).
 *
 * Rules: the static layer (grid, map, roadmap) is drawn by a worker (view/layerworker.ts) into a bitmap a margin
 * larger than the view; every frame draws the last bitmap moved and scaled to the current camera, then the live
 * layer (overlay.ts) on top, and asks the worker for a new bitmap when the view has left the old one or its scale
 * changed (one request in flight at a time). Without workers the layer is drawn on the page. Frames are drawn on
 * requestAnimationFrame only when something changed. The canvas exposes what it drew (data-drawn-*,
 * an accessible summary) and its camera (data-camera) so tests and assistive tools can read the view.
 */
import { h } from "../dom";
import { bind, onLanguage, t, type Key } from "../i18n/i18n";
import { GetStatusReply, MotionMode, MoveAbsRequest, SetFrmPltfRequest } from "../pltf";
import { type Bounds, countKinds, KINDS, type MapScene, MapParseError, parseMap, sceneBounds } from "../scene/map";
import { parseRoadmap, type Roadmap } from "../scene/roadmap";
import type { PlatformSession, TruthEvent } from "../session/session";
import { type Camera, fit, panBy, toWorld, viewBounds, zoomAt } from "../view/camera";
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
} from "../view/maprender";
import {
  type Box,
  changedWindow,
  dirtyPart,
  HeadTailBoxes,
  patchCounts,
  union,
  windowBox,
  windowSize,
} from "../view/scenediff";
import {
  drawFlag,
  drawPlatform,
  drawStatus,
  footprint,
  type Footprint,
  type OverlayOptions,
  type Pose,
  type UsSensor,
} from "../view/overlay";
import { liveKey } from "../view/livekey";
import { guard } from "./control";
import type { ViewOptions } from "./viewoptions";

type Tool = "pan" | "zoomArea" | "shift" | "flag" | "edit";

/** An editor's hold on the view (editor/editpanel.ts, editor/roadmappanel.ts): pointer events in world mm, and its own drawing. */
export interface EditHooks {
  /**
   * The platform's document this editor shows its own in place of: a GET_MAP (GET_ROADMAP) answered while the
   * editor is open leaves that editor's document on the view; the other document is still the platform's, so
   * the roadmap editor places its stations over the platform's map even when that map came late.
   */
  readonly shows: "map" | "roadmap";
  /** `button`: 0 left, 2 right (a right-click finishes a polygon) */
  down(x: number, y: number, pxPerMm: number, button: number): void;
  move(x: number, y: number): void;
  up(x: number, y: number): void;
  draw(ctx: CanvasRenderingContext2D, cam: Camera): void;
}
/** A region of the static layer an edit redrew on the page: its image and where it goes (CSS px of the layer). */
interface LayerPatch {
  image: HTMLCanvasElement;
  x: number;
  y: number;
  width: number;
  height: number;
}
const MARGIN = 256; // px of static layer beyond each edge of the view
/** patches kept over one layer image before they are flattened into a copy of it */
const PATCHES_MAX = 16;
/** an edit touching at most this many objects goes to the worker as a patch of its base (issue 20) */
const PATCH_MAX = 2000;
/** px around an edit's box redrawn on the page: the front-side ticks (6 px), the widest stroke (4 px) */
const DIRTY_PAD = 10;
/** ms after the worker's first layer of a new base before the page builds its own index of it (for edits) */
const PAGE_INDEX_DELAY_MS = 300;

export class MapView {
  readonly root: HTMLElement;
  readonly canvas: HTMLCanvasElement;
  readonly summary: HTMLElement;
  cam: Camera = { cx: 0, cy: 0, scale: 0.05, width: 800, height: 600 };
  tool: Tool = "pan";
  scene: MapScene | null = null;
  /** the scene's index for drawing on the page (built only without a worker, or for the benchmark's baseline) */
  prepared: Prepared | null = null;
  bounds: Bounds | null = null;
  roadmap: Roadmap | null = null;
  status: GetStatusReply | null = null;
  /** the live key (view/livekey.ts) of the last status that asked for a redraw */
  private drawnKey = "";
  flag: Pose | null = null;
  footprint: Footprint = footprint(650, 430, 100);
  usSensors: UsSensor[] = [];
  drawn: Record<string, number> = {};
  /** ms spent in the last frames' drawing (the benchmark reads it) */
  frameTimes: number[] = [];
  /**
   * the last static layer: its image, the camera it was drawn for (margin included), the document version, and
   * the regions edits redrew on the page over the image since (drawn on top, in order; issue 20)
   */
  layer: { image: CanvasImageSource; cam: Camera; version: number; patches?: LayerPatch[] } | null = null;
  /** ms the layer worker took for its last layers (the benchmark reads it) */
  layerTimes: number[] = [];
  /** draw the static layer on the page in every frame (the benchmark's baseline) */
  syncLayers = false;
  private worker: Worker | null = null;
  /** the scene the worker holds as its base (its objects as they were then) and their counts per kind */
  private base: {
    scene: MapScene;
    objects: MapScene["objects"];
    counts: Record<string, number>;
    bounds: Bounds | null;
    /** the boxes of the base's heads and tails (built with the page's grids): exact bounds after any edit */
    boxes?: HeadTailBoxes;
    /** the page's grids and boxes are asked for */
    indexing?: boolean;
  } | null = null;
  /** the current scene's counts per kind */
  private counts: Record<string, number> = {};
  /** the page's index of the base (built once, a while after the base is drawn): an edit is redrawn here at once */
  private pageBase: { of: MapScene["objects"]; prep: Prepared } | null = null;
  /** the world box of the objects the current patch touches (they differ from the base there) */
  private patchBox: Box | null = null;
  /** the layer was drawn on the page for an edit: the worker's layer of the version is still to come */
  private countsStale = false;
  private inFlight: { id: number; version: number } | null = null;
  private requestId = 0;
  private version = 0;
  private dirty = true;
  private scheduled = false;
  private drag: { x: number; y: number; button: number; cam: Camera; pose?: Pose } | null = null;
  private area: { x0: number; y0: number; x1: number; y1: number } | null = null;
  private toolButtons = new Map<Tool, HTMLButtonElement>();
  private fitted = false;
  private message: HTMLElement;
  /** the optional ground truth (control channel) and its readout, shown only once it has been asked for */
  truth: TruthEvent | null = null;
  private truthText: HTMLElement;
  /** set while the map editor is open: the view shows its document and hands it the pointer in tool "edit" */
  editHooks: EditHooks | null = null;

  constructor(
    readonly session: PlatformSession,
    readonly options: ViewOptions,
  ) {
    this.canvas = h("canvas", { role: "img", tabindex: "0", class: "map-canvas" });
    bind(this.canvas, "map.canvas", { text: false });
    this.summary = h("p", { class: "map-summary", id: "map-summary" });
    this.canvas.setAttribute("aria-describedby", "map-summary");
    this.message = h("p", { class: "map-message", role: "status", "aria-live": "polite" });
    bind(this.message, "map.messages", { text: false });
    const toolbar = h("div", { role: "toolbar", class: "map-tools" });
    bind(toolbar, "map.tools", { text: false });
    const act = (key: Key, fn: () => void, shortcut = "") => {
      const b = h("button", { type: "button", "aria-keyshortcuts": shortcut || false });
      bind(b, key);
      b.addEventListener("click", fn);
      toolbar.append(b);
      return b;
    };
    act("map.refresh", () => session.refreshDocuments(), "R");
    act("map.zoomAll", () => this.zoomAll(), "A");
    act("map.zoomIn", () => this.zoom(1.5), "+");
    act("map.zoomOut", () => this.zoom(1 / 1.5), "-");
    const toolButton = (tool: Tool, key: Key) => {
      const b = act(key, () => this.setTool(this.tool === tool ? "pan" : tool));
      b.setAttribute("aria-pressed", String(tool === this.tool));
      this.toolButtons.set(tool, b);
    };
    toolButton("zoomArea", "map.zoomArea");
    toolButton("pan", "map.pan");
    toolButton("shift", "map.shift");
    toolButton("flag", "map.flag");
    // issue 33: shifting the platform and the target flag send commands: only while this tab may command
    guard(session, this.toolButtons.get("shift")!);
    guard(session, this.toolButtons.get("flag")!);
    this.truthText = h("p", { class: "map-truth", role: "status", hidden: true });
    bind(this.truthText, "truth.title", { text: false });
    this.root = h(
      "section",
      { class: "map-view" },
      toolbar,
      h("div", { class: "map-frame" }, this.canvas),
      this.message,
      this.summary,
      this.truthText,
    );
    bind(this.root, "view.map", { text: false });
    this.startWorker();
    this.wire();
    onLanguage(() => {
      this.updateSummary();
      this.showTruth();
    });
  }

  private wire(): void {
    const s = this.session;
    s.map.subscribe((m) => {
      if (this.editHooks?.shows === "map") {
        return; // the map editor shows its own document
      }
      try {
        this.scene = parseMap(m.xml, m.name);
        this.bounds = sceneBounds(this.scene);
        this.prepared = null;
        this.say("");
      } catch (e) {
        this.scene = null;
        this.bounds = null;
        this.prepared = null;
        this.say(e instanceof MapParseError ? e.message : String(e));
      }
      this.documentsChanged();
      if (!this.fitted) {
        this.zoomAll();
      }
    });
    s.roadmap.subscribe((r) => {
      if (this.editHooks?.shows === "roadmap") {
        return; // the roadmap editor shows its own document
      }
      try {
        this.roadmap = parseRoadmap(r.xml, r.name);
      } catch (e) {
        this.roadmap = null;
        this.say(String((e as Error).message));
      }
      this.documentsChanged();
    });
    s.status.subscribe((st) => {
      this.status = st;
      // a status that changes nothing the map draws is not redrawn (view/livekey.ts)
      const key = liveKey(st, this.overlayOptions());
      if (key === this.drawnKey) {
        return;
      }
      this.drawnKey = key;
      if (this.options.centerPlatform) {
        this.cam = { ...this.cam, cx: st.estX, cy: st.estY };
      }
      this.invalidate();
    });
    s.truth.subscribe((ev) => {
      this.truth = ev;
      this.showTruth();
      this.invalidate();
    });
    this.options.changed.subscribe(() => {
      this.version++;
      this.drawnKey = ""; // the next status is drawn (and centred on) whatever it shows
      this.invalidate();
    });
    new ResizeObserver(() => this.resize()).observe(this.canvas);
    this.canvas.addEventListener(
      "wheel",
      (e) => {
        e.preventDefault();
        this.zoom(e.deltaY < 0 ? 1.2 : 1 / 1.2, e.offsetX, e.offsetY);
      },
      { passive: false },
    );
    this.canvas.addEventListener("pointerdown", (e) => this.down(e));
    this.canvas.addEventListener("pointermove", (e) => this.move(e));
    this.canvas.addEventListener("pointerup", (e) => this.up(e));
    this.canvas.addEventListener("contextmenu", (e) => e.preventDefault());
    this.canvas.addEventListener("keydown", (e) => {
      const step = 60;
      const moves: Record<string, [number, number]> = { h: [step, 0], l: [-step, 0], k: [0, step], j: [0, -step] };
      const m = moves[e.key];
      if (m !== undefined) {
        this.setCamera(panBy(this.cam, m[0], m[1]));
      }
    });
  }

  /** Show a document (the editor's): drawn like the platform's map until the editor closes. */
  showScene(scene: MapScene | null): void {
    this.scene = scene;
    this.bounds = scene === null ? null : (this.editedBounds(scene) ?? sceneBounds(scene));
    this.prepared = null;
    this.documentsChanged();
  }

  /**
   * The bounds of the base scene after an edit without a pass over every object (issue 20): the box of the base's
   * objects outside the changed window (head and tail boxes) and of the new ones; before those boxes are built,
   * the base's bounds grown by the new objects' box, exact when the objects gone lay strictly inside them (an
   * extreme point is then still held by an object kept). Null when neither holds: compute them.
   */
  private editedBounds(scene: MapScene): Bounds | null {
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

  private documentsChanged(): void {
    this.version++;
    if (!this.sendPatch()) {
      const s = this.scene;
      const packed = s === null ? null : pack(s, this.bounds); // one pass: segments, counts per kind (bounds known)
      this.counts = packed === null ? {} : packed.kinds;
      this.base =
        s === null ? null : { scene: s, objects: s.objects.slice(), counts: this.counts, bounds: this.bounds };
      // while the editor shows its document the page keeps a copy of the packed arrays (its own index of the base,
      // grids built later): an edit is drawn on the page from the first one on (issue 20)
      const kept = packed !== null && this.worker !== null && this.editHooks !== null ? copyPacked(packed) : null;
      this.pageBase = kept === null || this.base === null ? null : { of: this.base.objects, prep: preparePacked(kept) };
      this.patchBox = null;
      if (this.worker !== null) {
        this.worker.postMessage(
          { type: "scene", scene: packed, roadmap: this.roadmap },
          packed === null ? [] : transfers(packed),
        );
      }
    }
    this.invalidate();
  }

  /**
   * The same scene edited (the editor changes its document's object list by whole objects): only the objects in
   * the changed window go to the worker, which draws them over its base. False when a whole scene must go.
   */
  private sendPatch(): boolean {
    const s = this.scene;
    const b = this.base;
    if (this.worker === null || s === null || b === null || b.scene !== s) {
      return false;
    }
    const w = changedWindow(b.objects, s.objects);
    if (windowSize(w) > PATCH_MAX) {
      return false;
    }
    this.counts = patchCounts(b.counts, b.objects, s.objects, w);
    const added = pack({ ...s, objects: s.objects.slice(w.start, w.curEnd) });
    const patch: ScenePatch = {
      bounds: this.bounds,
      hideFrom: w.start,
      hideTo: w.baseEnd,
      added,
      addedCount: w.curEnd - w.start,
    };
    const box = windowBox(b.objects, s.objects, w);
    this.patchLayer(patch, union(box, this.patchBox));
    this.patchBox = box;
    this.worker.postMessage({ type: "patch", patch, roadmap: this.roadmap }, transfers(added));
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
    if (l === null || pb === null || pb.of !== this.base?.objects || l.version !== this.version - 1) {
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
      drawStatic(ctx, part.cam, applyPatch(pb.prep, patch), this.roadmap, this.layers());
      patches.push({ image, x: part.x, y: part.y, width: part.cam.width, height: part.cam.height });
    }
    this.layer =
      patches.length > PATCHES_MAX
        ? this.flatten(l, patches)
        : { image: l.image, cam: l.cam, version: this.version, patches };
    this.countsStale = true; // what is in view per kind: the worker's layer of this version says
  }

  /** One image of a layer and its patches (when edits came faster than the worker's layers for long). */
  private flatten(l: NonNullable<MapView["layer"]>, patches: readonly LayerPatch[]): NonNullable<MapView["layer"]> {
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
    return { image: canvas, cam: l.cam, version: this.version };
  }

  /** Ask the worker for a layer of the current version and view, unless one is being drawn. */
  private askWorker(): void {
    if (this.worker !== null && !this.syncLayers && this.inFlight === null) {
      this.inFlight = { id: ++this.requestId, version: this.version };
      const dpr = window.devicePixelRatio || 1;
      this.worker.postMessage({
        type: "render",
        id: this.requestId,
        cam: this.layerCamera(),
        layers: this.layers(),
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
    if (this.worker === null || b === null || this.editHooks === null || b.indexing === true) {
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
      this.worker = new Worker(new URL("../view/layerworker.ts", import.meta.url), { type: "module" });
    } catch {
      this.worker = null;
      return;
    }
    this.worker.onmessage = (e: MessageEvent) => {
      const m = e.data as { id: number; cam: Camera; bitmap: ImageBitmap; drawn: Record<string, number>; ms: number };
      const asked = this.inFlight;
      this.inFlight = null;
      if (asked === null || asked.id !== m.id || (this.layer !== null && asked.version < this.layer.version)) {
        m.bitmap.close(); // not asked for, or older than the layer drawn on the page for an edit
        this.invalidate();
        return;
      }
      if (this.layer?.image instanceof ImageBitmap) {
        this.layer.image.close();
      }
      this.layer = { image: m.bitmap, cam: m.cam, version: asked.version };
      this.countsStale = this.countsStale && asked.version !== this.version;
      this.layerTimes.push(m.ms);
      if (this.layerTimes.length > 1000) {
        this.layerTimes.splice(0, 500);
      }
      this.countVisible(m.drawn);
      this.buildPageBase();
      this.invalidate();
    };
    this.worker.onerror = () => {
      this.worker = null; // drawn on the page from now on
      this.inFlight = null;
      this.invalidate();
    };
  }

  /** The true pose beside the estimate and the injected faults, in words (guide units: mm, degrees). */
  private showTruth(): void {
    const ev = this.truth;
    if (ev === null) {
      return;
    }
    this.truthText.hidden = false;
    if (ev.event === "truth_lost" || ev.true === undefined) {
      this.truthText.textContent = t("truth.lost", { control: ev.control, detail: ev.detail ?? "" });
      return;
    }
    const [x, y, a] = ev.true;
    const faults = (ev.faults ?? []).map((f) => `${f.kind} ${f.target}${f.value == null ? "" : ` ${f.value}`}`);
    this.truthText.textContent = `${t("truth.pose", { x: Math.round(x), y: Math.round(y), angle: a.toFixed(1) })}; ${
      faults.length === 0 ? t("truth.noFaults") : t("truth.faults", { list: faults.join(", ") })
    }`;
  }

  private say(text: string): void {
    this.message.textContent = text;
  }

  setTool(tool: Tool): void {
    this.tool = tool;
    for (const [k, b] of this.toolButtons) {
      b.setAttribute("aria-pressed", String(k === tool));
    }
    if (tool === "flag" && this.flag === null) {
      const st = this.status;
      this.flag = st
        ? { x: st.estX, y: st.estY, angle: st.estAngle / 1000 }
        : { x: this.cam.cx, y: this.cam.cy, angle: 0 };
    }
    this.canvas.dataset.tool = tool;
    this.invalidate();
  }

  private resize(): void {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    this.canvas.width = Math.max(1, Math.round(r.width * dpr));
    this.canvas.height = Math.max(1, Math.round(r.height * dpr));
    this.cam = { ...this.cam, width: r.width, height: r.height };
    if (!this.fitted && this.bounds) {
      this.zoomAll();
    }
    this.invalidate();
  }

  setCamera(cam: Camera): void {
    this.cam = cam;
    this.invalidate();
  }

  zoomAll(): void {
    const b = this.bounds;
    if (b && this.cam.width > 1) {
      this.cam = fit(this.cam, b);
      this.fitted = true;
    }
    this.invalidate();
  }

  zoom(factor: number, sx = this.cam.width / 2, sy = this.cam.height / 2): void {
    this.setCamera(zoomAt(this.cam, factor, sx, sy));
  }

  // ---- pointer tools
  private down(e: PointerEvent): void {
    this.canvas.setPointerCapture(e.pointerId);
    this.canvas.focus();
    this.drag = { x: e.offsetX, y: e.offsetY, button: e.button, cam: this.cam };
    if (this.tool === "edit" && this.editHooks !== null) {
      const [wx, wy] = toWorld(this.cam, e.offsetX, e.offsetY);
      this.editHooks.down(wx, wy, this.cam.scale, e.button);
      return;
    }
    if (this.tool === "shift" && this.status) {
      this.drag.pose = { x: this.status.estX, y: this.status.estY, angle: this.status.estAngle / 1000 };
    } else if (this.tool === "flag" && this.flag) {
      this.drag.pose = { ...this.flag };
    } else if (this.tool === "zoomArea") {
      this.area = { x0: e.offsetX, y0: e.offsetY, x1: e.offsetX, y1: e.offsetY };
    }
  }

  /** The pose a drag gives: left button moves it, right button turns it toward the pointer. */
  private dragged(e: PointerEvent, d = this.drag): Pose | null {
    if (d?.pose === undefined) {
      return null;
    }
    const [wx, wy] = toWorld(this.cam, e.offsetX, e.offsetY);
    if (d.button === 2) {
      const angle = (Math.atan2(wy - d.pose.y, wx - d.pose.x) * 180) / Math.PI;
      return { ...d.pose, angle: Math.round(angle * 10) / 10 };
    }
    const [w0x, w0y] = toWorld(this.cam, d.x, d.y);
    return { x: Math.round(d.pose.x + wx - w0x), y: Math.round(d.pose.y + wy - w0y), angle: d.pose.angle };
  }

  private ghost: Pose | null = null;

  private move(e: PointerEvent): void {
    const d = this.drag;
    if (d === null) {
      return;
    }
    if (this.tool === "edit" && this.editHooks !== null) {
      const [wx, wy] = toWorld(this.cam, e.offsetX, e.offsetY);
      this.editHooks.move(wx, wy);
      this.invalidate();
      return;
    }
    if (this.tool === "pan" || ((this.tool === "shift" || this.tool === "flag") && d.pose === undefined)) {
      this.setCamera(panBy(d.cam, e.offsetX - d.x, e.offsetY - d.y));
    } else if (this.tool === "zoomArea" && this.area) {
      this.area.x1 = e.offsetX;
      this.area.y1 = e.offsetY;
      this.invalidate();
    } else if (this.tool === "flag") {
      this.flag = this.dragged(e);
      this.invalidate();
    } else if (this.tool === "shift") {
      this.ghost = this.dragged(e);
      this.invalidate();
    }
  }

  private up(e: PointerEvent): void {
    const d = this.drag;
    this.drag = null;
    if (d === null) {
      return;
    }
    if (this.tool === "edit" && this.editHooks !== null) {
      const [wx, wy] = toWorld(this.cam, e.offsetX, e.offsetY);
      this.editHooks.up(wx, wy);
      this.invalidate();
      return;
    }
    if (this.tool === "zoomArea" && this.area) {
      const a = this.area;
      this.area = null;
      if (Math.abs(a.x1 - a.x0) > 4 && Math.abs(a.y1 - a.y0) > 4) {
        const [x0, y0] = toWorld(this.cam, Math.min(a.x0, a.x1), Math.max(a.y0, a.y1));
        const [x1, y1] = toWorld(this.cam, Math.max(a.x0, a.x1), Math.min(a.y0, a.y1));
        this.setCamera(fit(this.cam, { minX: x0, minY: y0, maxX: x1, maxY: y1 }, 0));
      }
      this.invalidate();
      return;
    }
    const pose = this.dragged(e, d);
    if (pose === null) {
      return;
    }
    if (this.tool === "shift") {
      this.ghost = null;
      // guide 5.3: "The platform can be shifted by drag and drop. The frame is rotated with a right-click."
      this.send(
        new SetFrmPltfRequest({ x: pose.x, y: pose.y, angle: Math.round(pose.angle * 1000) }),
        "map.sentShift",
        pose,
      );
    } else if (this.tool === "flag") {
      this.flag = pose;
      this.sendFlag();
    }
    this.invalidate();
  }

  /** guide 5.3: "Used in motion mode Automatic, the platform will move to a specified location." */
  sendFlag(): void {
    const f = this.flag;
    if (f === null) {
      return;
    }
    if (this.status?.motionMode !== MotionMode.MODE_MOTION_AUTOMATIC) {
      this.say(t("map.flagNeedsAutomatic"));
      return;
    }
    this.send(new MoveAbsRequest({ x: f.x, y: f.y, angle: Math.round(f.angle * 1000) }), "map.sentFlag", f);
  }

  private send(req: SetFrmPltfRequest | MoveAbsRequest, key: Key, p: Pose): void {
    try {
      this.session.send(req);
      this.say(t(key, { x: p.x, y: p.y, angle: p.angle.toFixed(1) }));
    } catch (e) {
      this.say((e as Error).message);
    }
  }

  // ---- drawing
  invalidate(): void {
    this.dirty = true;
    if (!this.scheduled) {
      this.scheduled = true;
      requestAnimationFrame(() => {
        this.scheduled = false;
        if (this.dirty) {
          this.render();
        }
      });
    }
  }

  private layers(): Layers {
    const o = this.options;
    return {
      grid: o.grid,
      map: o.mapLayers.map,
      roadmap: o.mapLayers.roadmap,
      labels: o.mapLayers.hiddenlabel,
      kinds: o.mapLayers,
    };
  }

  /** Does the layer show the current view at its own scale, margin included? */
  private covers(l: { cam: Camera; version: number } | null): boolean {
    const c = this.cam;
    if (l === null || l.version !== this.version || l.cam.scale !== c.scale) {
      return false;
    }
    return (
      Math.abs((c.cx - l.cam.cx) * c.scale) <= MARGIN &&
      Math.abs((c.cy - l.cam.cy) * c.scale) <= MARGIN &&
      l.cam.width >= c.width + 2 * MARGIN &&
      l.cam.height >= c.height + 2 * MARGIN
    );
  }

  private layerCamera(): Camera {
    const c = this.cam;
    return { ...c, width: c.width + 2 * MARGIN, height: c.height + 2 * MARGIN };
  }

  /** Keep the static layer up to date: ask the worker (or draw here) when the view has left it. */
  private updateLayer(): void {
    if (this.covers(this.layer) && !this.countsStale) {
      return;
    }
    const dpr = window.devicePixelRatio || 1;
    if (this.worker !== null && !this.syncLayers) {
      this.askWorker();
      return;
    }
    if (this.prepared === null && this.scene !== null) {
      this.prepared = prepare(this.scene);
    }
    const big = this.layerCamera();
    const canvas = this.layer?.image instanceof HTMLCanvasElement ? this.layer.image : document.createElement("canvas");
    canvas.width = Math.round(big.width * dpr);
    canvas.height = Math.round(big.height * dpr);
    const ctx = canvas.getContext("2d")!;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const t0 = performance.now();
    const drawn = drawStatic(ctx, big, this.prepared, this.roadmap, this.layers());
    this.layerTimes.push(performance.now() - t0);
    this.layer = { image: canvas, cam: big, version: this.version };
    this.countVisible(drawn);
  }

  /** The last layer, moved and scaled to the current camera. */
  private drawLayer(ctx: CanvasRenderingContext2D): void {
    const l = this.layer;
    const c = this.cam;
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, c.width, c.height);
    if (l === null) {
      return;
    }
    const r = c.scale / l.cam.scale;
    const dx = c.width / 2 - (l.cam.width / 2) * r + (l.cam.cx - c.cx) * c.scale;
    const dy = c.height / 2 - (l.cam.height / 2) * r + (c.cy - l.cam.cy) * c.scale;
    ctx.imageSmoothingEnabled = false; // a scaled layer is a stand-in until the worker sends the new one
    ctx.drawImage(l.image, dx, dy, l.cam.width * r, l.cam.height * r);
    for (const p of l.patches ?? []) {
      ctx.drawImage(p.image, dx + p.x * r, dy + p.y * r, p.width * r, p.height * r);
    }
    ctx.imageSmoothingEnabled = true;
  }

  /** What lies in the view itself (the static layer also draws the margin). */
  private countVisible(drawnAll: Record<string, number>): void {
    const whole = this.bounds;
    const v = viewBounds(this.cam);
    const inView =
      whole != null && v.minX <= whole.minX && v.minY <= whole.minY && v.maxX >= whole.maxX && v.maxY >= whole.maxY;
    this.drawn = drawnAll;
    this.canvas.dataset.complete = String(inView);
    for (const k of [...KINDS, "station", "edge", "pathpoint"]) {
      this.canvas.dataset[`drawn${k[0].toUpperCase()}${k.slice(1)}`] = String(drawnAll[k] ?? 0);
    }
    this.updateSummary();
  }

  private updateSummary(): void {
    const scene = this.scene;
    if (scene === null) {
      this.summary.textContent = t("map.none");
      return;
    }
    const counts = this.counts;
    const parts = KINDS.filter((k) => counts[k] > 0).map(
      (k) => `${t(`kind.${k}` as Key)}: ${this.drawn[k] ?? 0}/${counts[k]}`,
    );
    if (this.roadmap) {
      parts.push(`${t("kind.station")}: ${this.drawn.station ?? 0}/${this.roadmap.stations.length}`);
      parts.push(`${t("kind.edge")}: ${this.drawn.edge ?? 0}/${this.roadmap.edges.length}`);
    }
    this.summary.textContent = `${t("map.summary", { name: scene.name || "-" })} ${parts.join(", ")}`;
  }

  /** The live layers the view options show (guide 5.2 View). */
  private overlayOptions(): OverlayOptions {
    const o = this.options;
    return {
      showEstimated: o.showEstimated,
      showDesired: o.showDesired,
      scan: o.localization,
      ultrasonic: o.ultrasonic,
      path: o.planning,
      localization: o.localization,
      planObstacles: o.planObstacles,
    };
  }

  render(): void {
    const t0 = performance.now();
    this.dirty = false;
    const ctx = this.canvas.getContext("2d");
    if (ctx === null) {
      return;
    }
    const c = this.cam;
    const dpr = window.devicePixelRatio || 1;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    if (this.syncLayers) {
      this.layer = null;
    }
    this.updateLayer();
    this.drawLayer(ctx);
    const overlay = this.overlayOptions();
    if (this.status) {
      const live = drawStatus(ctx, c, this.status, this.footprint, this.usSensors, overlay);
      this.canvas.dataset.drawnScan = String(live.scan);
      this.canvas.dataset.drawnUltrasonic = String(live.ultrasonic);
      this.canvas.dataset.drawnPath = String(live.path);
      this.canvas.dataset.drawnPlanobst = String(live.planobst);
    }
    const tr = this.truth;
    if (tr?.event === "truth" && tr.true !== undefined && this.options.truth) {
      const [x, y, angle] = tr.true;
      drawPlatform(ctx, c, { x, y, angle }, this.footprint, "#757575", true);
      this.canvas.dataset.truth = `${x},${y},${angle}`;
    } else {
      delete this.canvas.dataset.truth;
    }
    if (this.ghost) {
      ctx.globalAlpha = 0.6;
      drawStatus(
        ctx,
        c,
        Object.assign(new GetStatusReply(), {
          estX: this.ghost.x,
          estY: this.ghost.y,
          estAngle: this.ghost.angle * 1000,
        }),
        this.footprint,
        [],
        {
          ...overlay,
          showDesired: false,
          scan: false,
          ultrasonic: false,
          path: false,
          localization: false,
          planObstacles: false,
        },
      );
      ctx.globalAlpha = 1;
    }
    if (this.flag && this.tool === "flag") {
      drawFlag(ctx, c, this.flag);
      this.canvas.dataset.flag = `${this.flag.x},${this.flag.y},${this.flag.angle}`;
    }
    this.editHooks?.draw(ctx, c);
    if (this.area) {
      const a = this.area;
      ctx.strokeStyle = "#1565c0";
      ctx.setLineDash([4, 3]);
      ctx.strokeRect(Math.min(a.x0, a.x1), Math.min(a.y0, a.y1), Math.abs(a.x1 - a.x0), Math.abs(a.y1 - a.y0));
      ctx.setLineDash([]);
    }
    this.canvas.dataset.camera = JSON.stringify({
      cx: c.cx,
      cy: c.cy,
      scale: c.scale,
      width: c.width,
      height: c.height,
    });
    this.frameTimes.push(performance.now() - t0);
    this.canvas.dataset.layer = this.covers(this.layer) ? "current" : "stale";
    if (this.frameTimes.length > 1000) {
      this.frameTimes.splice(0, 500);
    }
  }
}

export { countKinds };
