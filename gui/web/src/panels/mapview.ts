/**
 * The map view (guide 5.3): the platform's map and roadmap, the live platform over them, and the tools to move
 * the view and to command the platform from it. Three parts with their own state, put together here:
 *
 * - `map/controller.ts`: the camera and the tools (toolbar, pointer, wheel, keys; shift, flag, zoom to area);
 * - `map/layercache.ts`: the static layer (grid, map, roadmap) drawn by the layer worker, with its edit patches;
 * - `map/renderer.ts`: the frames (that layer, then the live layer), the accessible summary, the ground truth.
 *
 * Rules: the view is a panel like the others: it subscribes to the session's topics (map, roadmap, status, truth,
 * params) and to `edited`, on which an open editor publishes the document it shows in place of the platform's
 * (session/edited.ts); it alone writes what is shown (`map/shown.ts`). The canvas says what it drew (data-drawn-*,
 * data-camera, an accessible summary). The benchmarks and the browser tests read the view through `debug`
 * (window.pltf.map), a small read-only surface, never through its parts.
 */
import { h } from "../dom";
import { bind, onLanguage } from "../i18n/i18n";
import type { GetMapReply, GetRoadmapReply, GetStatusReply } from "../pltf";
import { MapParseError, type MapScene, parseMap, sceneBounds } from "../scene/map";
import { parseRoadmap } from "../scene/roadmap";
import type { EditedDocument } from "../session/edited";
import { bodyAt, type FleetBody } from "../session/fleet";
import type { PlatformSession } from "../session/session";
import { type Camera, toWorld } from "../view/camera";
import type { PlacedLabel } from "../view/labels";
import { liveKey } from "../view/livekey";
import { MapController, type Tool } from "./map/controller";
import { LayerCache } from "./map/layercache";
import { layersOf, MapRenderer, overlayOf } from "./map/renderer";
import { nothingShown } from "./map/shown";
import type { ViewOptions } from "./viewoptions";

export type { Tool } from "./map/controller";

/** a pointer that moved less than this (px) between down and up clicked */
const CLICK_PX = 4;

/**
 * The map view as the benchmarks and the browser tests see it (window.pltf.map): read-only state, and the few
 * commands they drive (the camera as the toolbar moves it, a frame drawn now, the no-edit baseline of the editor
 * benchmark, the on-page baseline of the pan/zoom benchmark). Nothing here is needed by the GUI itself.
 */
export interface MapDebug {
  readonly canvas: HTMLCanvasElement;
  /** a copy of the current camera */
  readonly cam: Readonly<Camera>;
  /** the scene shown (the platform's map, or the open map editor's document) */
  readonly scene: MapScene | null;
  /** the documents' version: bumped by every change of what the static layer shows */
  readonly version: number;
  /** the version and camera of the last static layer (null before the first) */
  readonly layer: { readonly version: number; readonly cam: Camera } | null;
  setCamera(cam: Camera): void;
  zoom(factor: number): void;
  zoomAll(): void;
  /** draw a frame now (not at the next animation frame) */
  render(): void;
  /** show a scene as an editor's edit would (the editor benchmark shows the same scene again: its baseline) */
  showScene(scene: MapScene | null): void;
  /** draw the static layer on the page in every frame (the pan/zoom benchmark's baseline) instead of the worker */
  setSyncLayers(on: boolean): void;
  /** the ms the last static layers took to draw (worker or page), since the last call */
  takeLayerTimes(): number[];
  /** the texts (station names, map labels) the static layer drew, their boxes in the canvas's CSS px (issue 35) */
  labels(): PlacedLabel[];
}

export class MapView {
  readonly root: HTMLElement;
  readonly canvas: HTMLCanvasElement;
  readonly debug: MapDebug;
  private readonly shown = nothingShown();
  /** the open editor's document, if one is open (what the platform's replies leave alone) */
  private editing: EditedDocument | null = null;
  /** the live key (view/livekey.ts) of the last status that asked for a redraw */
  private drawnKey = "";
  private readonly message: HTMLElement;
  private readonly controller: MapController;
  private readonly cache: LayerCache;
  private readonly renderer: MapRenderer;
  /** a click on a fleet platform's body (issue 30) selects it: panels/fleet.ts sets this */
  onPick: ((target: string) => void) | null = null;

  constructor(
    private readonly session: PlatformSession,
    private readonly options: ViewOptions,
  ) {
    this.canvas = h("canvas", { role: "img", tabindex: "0", class: "map-canvas" });
    bind(this.canvas, "map.canvas", { text: false });
    const summary = h("p", { class: "map-summary", id: "map-summary" });
    this.canvas.setAttribute("aria-describedby", "map-summary");
    this.message = h("p", { class: "map-message", role: "status", "aria-live": "polite" });
    bind(this.message, "map.messages", { text: false });
    const invalidate = () => this.renderer.invalidate();
    this.controller = new MapController(this.canvas, session, this.shown, (s) => this.say(s), invalidate);
    const truthText = h("p", { class: "map-truth", role: "status", hidden: true });
    bind(truthText, "truth.title", { text: false });
    this.root = h(
      "section",
      { class: "map-view" },
      this.controller.toolbar,
      h("div", { class: "map-frame" }, this.canvas),
      this.message,
      summary,
      truthText,
    );
    bind(this.root, "view.map", { text: false });
    this.cache = new LayerCache({
      shown: this.shown,
      cam: () => this.controller.cam,
      layers: () => layersOf(options),
      drawn: (counts, labels) => this.renderer.countVisible(counts, labels),
      invalidate,
    });
    this.renderer = new MapRenderer(this.canvas, summary, truthText, this.shown, options, this.controller, this.cache);
    this.debug = this.debugSurface();
    this.subscribe();
    this.pickOnClick();
    onLanguage(() => {
      this.renderer.updateSummary();
      this.renderer.showTruth();
    });
  }

  /** the tool in use ("edit": the open editor has the pointer) */
  get tool(): Tool {
    return this.controller.tool;
  }

  setTool(tool: Tool): void {
    this.controller.setTool(tool);
  }

  zoomAll(): void {
    this.controller.zoomAll();
  }

  /** The panels' session now talks to another platform of the fleet (panels/fleet.ts): the last status is the one
   * before, so the selected platform is not drawn (its pose, scan, path) until the new one's first status. */
  switched(): void {
    this.shown.status = null;
    this.drawnKey = "";
    this.renderer.invalidate();
  }

  /** The fleet's platforms as the map draws them (issue 30; [] for one platform). */
  setFleet(bodies: FleetBody[]): void {
    this.shown.fleet = bodies;
    this.renderer.updateSummary();
    this.renderer.invalidate();
  }

  /** A click (no drag) with the pan tool on a platform's body selects it (panels/fleet.ts). */
  private pickOnClick(): void {
    let down: [number, number] | null = null;
    this.canvas.addEventListener("pointerdown", (e) => {
      down = e.button === 0 ? [e.offsetX, e.offsetY] : null;
    });
    this.canvas.addEventListener("pointerup", (e) => {
      const from = down;
      down = null;
      if (from === null || this.onPick === null || this.tool !== "pan" || this.shown.fleet.length === 0) {
        return;
      }
      if (Math.hypot(e.offsetX - from[0], e.offsetY - from[1]) > CLICK_PX) {
        return; // a drag: the view moved
      }
      const [wx, wy] = toWorld(this.controller.cam, e.offsetX, e.offsetY);
      const hit = bodyAt(this.shown.fleet, wx, wy, this.renderer.bodyRadius);
      if (hit !== null && !hit.selected) {
        this.onPick(hit.target);
      }
    });
  }

  /** guide 5.3: "Used in motion mode Automatic, the platform will move to a specified location." */
  sendFlag(): void {
    this.controller.sendFlag();
  }

  private subscribe(): void {
    const s = this.session;
    s.map.subscribe((m) => this.platformMap(m));
    s.roadmap.subscribe((r) => this.platformRoadmap(r));
    s.status.subscribe((st) => this.status(st));
    s.truth.subscribe((ev) => {
      this.shown.truth = ev;
      this.renderer.showTruth();
      this.renderer.invalidate();
    });
    this.options.changed.subscribe(() => {
      this.cache.optionsChanged();
      this.drawnKey = ""; // the next status is drawn (and centred on) whatever it shows
      this.renderer.invalidate();
    });
    // the platform's own geometry (guide 5.9 Geometry, UltraSonic) for the footprint and the ultrasonic sensors
    s.params.subscribe((r) => this.renderer.setGeometry(r));
    s.edited.subscribe((e) => this.edited(e));
    s.seeked.subscribe(() => this.seeked());
  }

  /** A recording's seek (session.seeked): what has no reply at the time shown is not drawn (the platform before
   * the first status, a map before the first GET_MAP reply), as live before the first reply. */
  private seeked(): void {
    const s = this.session;
    if (s.status.last === undefined && this.shown.status !== null) {
      this.shown.status = null;
      this.drawnKey = "";
      this.renderer.invalidate();
    }
    if (s.map.last === undefined && this.shown.scene !== null && this.editing?.shows !== "map") {
      this.shown.scene = null;
      this.shown.bounds = null;
      this.cache.sceneReplaced();
      this.cache.documentsChanged();
    }
    if (s.roadmap.last === undefined && this.shown.roadmap !== null && this.editing?.shows !== "roadmap") {
      this.shown.roadmap = null;
      this.cache.documentsChanged();
    }
  }

  private platformMap(m: GetMapReply): void {
    if (this.editing?.shows === "map") {
      return; // the map editor shows its own document
    }
    try {
      this.shown.scene = parseMap(m.xml, m.name);
      this.shown.bounds = sceneBounds(this.shown.scene);
      this.say("");
    } catch (e) {
      this.shown.scene = null;
      this.shown.bounds = null;
      this.say(e instanceof MapParseError ? e.message : String(e));
    }
    this.cache.sceneReplaced();
    this.cache.documentsChanged();
    if (!this.controller.hasFitted) {
      this.controller.zoomAll();
    }
  }

  private platformRoadmap(r: GetRoadmapReply): void {
    if (this.editing?.shows === "roadmap") {
      return; // the roadmap editor shows its own document
    }
    try {
      this.shown.roadmap = parseRoadmap(r.xml, r.name);
    } catch (e) {
      this.shown.roadmap = null;
      this.say(String((e as Error).message));
    }
    this.cache.documentsChanged();
  }

  private status(st: GetStatusReply): void {
    this.shown.status = st;
    // a status that changes nothing the map draws is not redrawn (view/livekey.ts)
    const key = liveKey(st, overlayOf(this.options));
    if (key === this.drawnKey) {
      return;
    }
    this.drawnKey = key;
    if (this.options.centerPlatform) {
      this.controller.centreOn(st.estX, st.estY);
    }
    this.renderer.invalidate();
  }

  /** An editor opened, changed or closed its document (`null`: the platform's documents come back when read). */
  private edited(e: EditedDocument | null): void {
    this.editing = e;
    this.shown.hooks = e?.hooks ?? null;
    if (e?.shows === "map") {
      this.showScene(e.scene);
    } else if (e?.shows === "roadmap") {
      this.shown.roadmap = e.roadmap;
      this.showScene(this.shown.scene); // redraws the static layer with the editor's roadmap
    }
  }

  /** Show a scene (the editor's): drawn like the platform's map until the editor closes. */
  private showScene(scene: MapScene | null): void {
    this.shown.scene = scene;
    this.shown.bounds = scene === null ? null : (this.cache.editedBounds(scene) ?? sceneBounds(scene));
    this.cache.sceneReplaced();
    this.cache.documentsChanged();
  }

  private say(text: string): void {
    this.message.textContent = text;
  }

  private debugSurface(): MapDebug {
    const { canvas, controller, cache, renderer, shown } = this;
    return Object.freeze({
      canvas,
      get cam() {
        return Object.freeze({ ...controller.cam });
      },
      get scene() {
        return shown.scene;
      },
      get version() {
        return cache.version;
      },
      get layer() {
        return cache.drawnFor;
      },
      setCamera: (cam: Camera) => controller.setCamera({ ...cam }),
      zoom: (factor: number) => controller.zoom(factor),
      zoomAll: () => controller.zoomAll(),
      render: () => renderer.render(),
      showScene: (scene: MapScene | null) => this.showScene(scene),
      setSyncLayers: (on: boolean) => cache.setSync(on),
      takeLayerTimes: () => cache.takeTimes(),
      labels: () => renderer.labels(),
    });
  }
}
