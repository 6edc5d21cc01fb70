/**
 * The map view's frames: the static layer (layercache.ts) moved to the camera, then the live layer (overlay.ts):
 * platform, scan, ultrasonic, path, the ground truth, the shift's ghost, the flag, the open editor's drawing and
 * the "zoom to area" rectangle. Frames are drawn on requestAnimationFrame only when something changed.
 *
 * Rules: drawing reads the camera, the documents and the options and changes none of them. The canvas says what
 * it drew (data-drawn-*, data-camera, data-layer, data-flag, data-truth, an accessible summary), so tests and
 * assistive tools can read the view without reaching into it. The texts the static layer drew (placed without
 * overlap, view/labels.ts) are kept with their boxes: `labels()` gives them in the canvas's px.
 */
import { type Key, t } from "../../i18n/i18n";
import { GetStatusReply, type GetPltfParamVecReply } from "../../pltf";
import { KINDS } from "../../scene/map";
import { drawnFootprint, type FleetBody, fleetData, reach } from "../../session/fleet";
import { type Camera, toScreen, viewBounds } from "../../view/camera";
import type { PlacedLabel } from "../../view/labels";
import type { Layers } from "../../view/maprender";
import {
  DEFAULT_FOOTPRINT,
  drawFlag,
  drawPlatform,
  drawStatus,
  type Footprint,
  type OverlayOptions,
  type UsSensor,
} from "../../view/overlay";
import type { ViewOptions } from "../viewoptions";
import type { Area, MapController } from "./controller";
import { type LayerCache, placement } from "./layercache";
import { platformGeometry } from "./platform";
import type { Shown } from "./shown";

/** The static layers the view options show (guide 5.7: grid, map, roadmap, map layers per kind). */
export function layersOf(o: ViewOptions): Layers {
  return {
    grid: o.grid,
    map: o.mapLayers.map,
    roadmap: o.mapLayers.roadmap,
    labels: o.mapLayers.hiddenlabel,
    kinds: o.mapLayers,
  };
}

/** The live layers the view options show (guide 5.2 View). */
export function overlayOf(o: ViewOptions): OverlayOptions {
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

/** The live layer of the shift's ghost: the footprint alone. */
const GHOST_ONLY: Partial<OverlayOptions> = {
  showDesired: false,
  scan: false,
  ultrasonic: false,
  path: false,
  localization: false,
  planObstacles: false,
};

export class MapRenderer {
  private dirty = true;
  private scheduled = false;
  private platform: Footprint = DEFAULT_FOOTPRINT;
  private usSensors: UsSensor[] = [];
  /** what the last static layer drew per kind */
  private drawn: Record<string, number> = {};
  /** the texts the last static layer drew (layer px) */
  private drawnLabels: readonly PlacedLabel[] = [];

  constructor(
    private readonly canvas: HTMLCanvasElement,
    private readonly summary: HTMLElement,
    private readonly truthText: HTMLElement,
    private readonly shown: Shown,
    private readonly options: ViewOptions,
    private readonly controller: MapController,
    private readonly cache: LayerCache,
  ) {}

  /** Take the platform's geometry from its parameters (GET_PLTF_PARAM_VEC). */
  setGeometry(r: Pick<GetPltfParamVecReply, "parameters">): void {
    const g = platformGeometry(r);
    this.platform = g.footprint;
    this.usSensors = g.usSensors;
    this.invalidate();
  }

  /** Ask for a frame (drawn at the next animation frame, once however often this is called before). */
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

  /** What lies in the view itself (the static layer also draws the margin). */
  countVisible(drawnAll: Record<string, number>, labels: readonly PlacedLabel[] = []): void {
    this.drawnLabels = labels;
    this.canvas.dataset.drawnLabels = String(drawnAll.labels ?? 0);
    this.canvas.dataset.hiddenLabels = String(drawnAll.labelsHidden ?? 0);
    const whole = this.shown.bounds;
    const v = viewBounds(this.controller.cam);
    const inView =
      whole != null && v.minX <= whole.minX && v.minY <= whole.minY && v.maxX >= whole.maxX && v.maxY >= whole.maxY;
    this.drawn = drawnAll;
    this.canvas.dataset.complete = String(inView);
    for (const k of [...KINDS, "station", "edge", "pathpoint"]) {
      this.canvas.dataset[`drawn${k[0].toUpperCase()}${k.slice(1)}`] = String(drawnAll[k] ?? 0);
    }
    this.updateSummary();
  }

  /** The accessible summary: the map's name and, per kind, the objects drawn of those there are. */
  updateSummary(): void {
    const { scene, roadmap } = this.shown;
    if (scene === null) {
      this.summary.textContent = t("map.none") + this.fleetText();
      return;
    }
    const counts = this.cache.counts;
    const parts = KINDS.filter((k) => counts[k] > 0).map(
      (k) => `${t(`kind.${k}` as Key)}: ${this.drawn[k] ?? 0}/${counts[k]}`,
    );
    if (roadmap) {
      parts.push(`${t("kind.station")}: ${this.drawn.station ?? 0}/${roadmap.stations.length}`);
      parts.push(`${t("kind.edge")}: ${this.drawn.edge ?? 0}/${roadmap.edges.length}`);
    }
    this.summary.textContent = `${t("map.summary", { name: scene.name || "-" })} ${parts.join(", ")}${this.fleetText()}`;
  }

  /** The fleet in words (issue 30): ". Platforms: alpha at x 4000 mm, y 10000 mm (selected), ..." */
  private fleetText(): string {
    const bodies = this.shown.fleet;
    if (bodies.length === 0) {
      return "";
    }
    const each = bodies.map((b) => {
      const at =
        b.pose === null ? t("fleet.noPose") : t("fleet.at", { x: Math.round(b.pose.x), y: Math.round(b.pose.y) });
      return `${b.name} ${at}${b.selected ? ` (${t("fleet.selected")})` : ""}`;
    });
    return `. ${t("fleet.onMap", { list: each.join(", ") })}`;
  }

  /**
   * The texts of the last static layer as the canvas shows them now: each box moved and scaled from the layer's
   * camera to the current one (the same until the view leaves the layer or its scale changes).
   */
  labels(): PlacedLabel[] {
    const l = this.cache.drawnFor;
    if (l === null) {
      return [];
    }
    const { dx, dy, r } = placement(l.cam, this.controller.cam);
    return this.drawnLabels.map((b) => ({
      ...b,
      x: dx + b.x * r,
      y: dy + b.y * r,
      w: b.w * r,
      h: b.h * r,
      tx: dx + b.tx * r,
      ty: dy + b.ty * r,
    }));
  }

  /** The radius (mm) within which a click hits a platform's body whose own footprint is not known yet. */
  get bodyRadius(): number {
    return reach(DEFAULT_FOOTPRINT);
  }

  /** A fleet body's footprint as drawn (session/fleet.ts `drawnFootprint`). */
  private outline = (b: FleetBody): Footprint => drawnFootprint(b, this.platform);

  /** The selected platform's footprint: a fleet's selected body's own (issue 30) once known, else the session's. */
  private get selectedFootprint(): Footprint {
    const selected = this.shown.fleet.find((b) => b.selected);
    return selected === undefined ? this.platform : this.outline(selected);
  }

  /** The true pose beside the estimate and the injected faults, in words (guide units: mm, degrees). */
  showTruth(): void {
    const ev = this.shown.truth;
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

  /** Draw one frame now. */
  render(): void {
    this.dirty = false;
    const ctx = this.canvas.getContext("2d");
    if (ctx === null) {
      return;
    }
    const c = this.controller.cam;
    const dpr = window.devicePixelRatio || 1;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    this.cache.update();
    this.cache.draw(ctx);
    this.drawLive(ctx);
    const area = this.controller.area;
    if (area !== null) {
      drawArea(ctx, area);
    }
    this.canvas.dataset.camera = JSON.stringify({
      cx: c.cx,
      cy: c.cy,
      scale: c.scale,
      width: c.width,
      height: c.height,
    });
    this.canvas.dataset.layer = this.cache.current ? "current" : "stale";
  }

  private drawLive(ctx: CanvasRenderingContext2D): void {
    const c = this.controller.cam;
    const overlay = overlayOf(this.options);
    const { status, truth: tr, hooks } = this.shown;
    const own = this.selectedFootprint;
    const live = status ? drawStatus(ctx, c, status, own, this.usSensors, overlay) : null;
    this.canvas.dataset.drawnScan = String(live?.scan ?? 0);
    this.canvas.dataset.drawnUltrasonic = String(live?.ultrasonic ?? 0);
    this.canvas.dataset.drawnPath = String(live?.path ?? 0);
    this.canvas.dataset.drawnPlanobst = String(live?.planobst ?? 0);
    // the platform drawn at its estimated pose (x, y mm, angle degrees); none before a first status
    if (status) {
      this.canvas.dataset.platform = `${status.estX},${status.estY},${status.estAngle / 1000}`;
    } else {
      delete this.canvas.dataset.platform;
    }
    if (tr?.event === "truth" && tr.true !== undefined && this.options.truth) {
      const [x, y, angle] = tr.true;
      drawPlatform(ctx, c, { x, y, angle }, own, "#757575", true);
      this.canvas.dataset.truth = `${x},${y},${angle}`;
    } else {
      delete this.canvas.dataset.truth;
    }
    const ghost = this.controller.ghost;
    if (ghost) {
      ctx.globalAlpha = 0.6;
      const st = Object.assign(new GetStatusReply(), { estX: ghost.x, estY: ghost.y, estAngle: ghost.angle * 1000 });
      drawStatus(ctx, c, st, own, [], { ...overlay, ...GHOST_ONLY });
      ctx.globalAlpha = 1;
    }
    const flag = this.controller.flag;
    if (flag && this.controller.tool === "flag") {
      drawFlag(ctx, c, flag);
      this.canvas.dataset.flag = `${flag.x},${flag.y},${flag.angle}`;
    }
    hooks?.draw(ctx, c);
    this.drawFleet(ctx, c, this.shown.fleet);
  }

  /**
   * The fleet's other platforms in their colours, each with its own footprint (its own parameters; the default
   * one until they are read), a name label on each (the selected one is drawn above).
   */
  private drawFleet(ctx: CanvasRenderingContext2D, c: Camera, bodies: FleetBody[]): void {
    if (bodies.length === 0) {
      delete this.canvas.dataset.fleet;
      return;
    }
    ctx.font = "12px sans-serif";
    for (const b of bodies) {
      if (b.pose === null) {
        continue;
      }
      if (!b.selected) {
        drawPlatform(ctx, c, b.pose, this.outline(b), b.colour, false);
      }
      const [sx, sy] = toScreen(c, b.pose.x, b.pose.y);
      const label = b.selected ? `▶ ${b.name}` : b.name;
      ctx.lineWidth = 3;
      ctx.strokeStyle = "#ffffff";
      ctx.strokeText(label, sx + 8, sy - 8);
      ctx.fillStyle = b.colour;
      ctx.fillText(label, sx + 8, sy - 8);
    }
    ctx.lineWidth = 1;
    this.canvas.dataset.fleet = fleetData(bodies, this.outline);
  }
}

/** The rectangle of a "zoom to area" drag, dashed. */
function drawArea(ctx: CanvasRenderingContext2D, a: Readonly<Area>): void {
  ctx.strokeStyle = "#1565c0";
  ctx.setLineDash([4, 3]);
  ctx.strokeRect(Math.min(a.x0, a.x1), Math.min(a.y0, a.y1), Math.abs(a.x1 - a.x0), Math.abs(a.y1 - a.y0));
  ctx.setLineDash([]);
}
