/**
 * The map view's camera and tools (guide 5.3): the toolbar (refresh, zoom all, zoom in/out, zoom to area, pan,
 * shift the platform, target flag), the pointer, the wheel and the h/j/k/l keys. Shifting the platform sends
 * CMD_SET_FRM_PLTF, the flag CMD_MOVE_ABS in Automatic; in the tool "edit" the pointer goes to the open editor.
 *
 * Rules: this module owns the camera and changes it only through view/camera.ts; it reads the documents and the
 * status the view was last given (`Shown`) and never changes them; whatever it changes is drawn at the next frame
 * it asks for (`invalidate`).
 */
import { h } from "../../dom";
import { bind, type Key, t } from "../../i18n/i18n";
import { MotionMode, MoveAbsRequest, SetFrmPltfRequest } from "../../pltf";
import type { PlatformSession } from "../../session/session";
import { type Camera, fit, panBy, toWorld, zoomAt } from "../../view/camera";
import type { Pose } from "../../view/overlay";
import { guard } from "../control";
import { draggedPose } from "./platform";
import { icon } from "../../ui/icons";
import type { Shown } from "./shown";

export type Tool = "pan" | "zoomArea" | "shift" | "flag" | "edit";

/** The rectangle being dragged with "zoom to area", canvas CSS px. */
export interface Area {
  x0: number;
  y0: number;
  x1: number;
  y1: number;
}

interface Drag {
  x: number;
  y: number;
  button: number;
  cam: Camera;
  pose?: Pose;
}

/** px the h/j/k/l keys pan by, and their directions */
/** guide 5.3 Map tools: each tool's use, its tooltip (issue 35). */
const MAP_TIPS: Partial<Record<Key, Key>> = {
  "map.refresh": "map.tipRefresh",
  "map.zoomAll": "map.tipZoomAll",
  "map.zoomIn": "map.tipZoomIn",
  "map.zoomOut": "map.tipZoomOut",
  "map.zoomArea": "map.tipZoomArea",
  "map.pan": "map.tipPan",
  "map.shift": "map.tipShift",
  "map.flag": "map.tipFlag",
};

const KEY_STEP = 60;
const KEY_MOVES: Record<string, [number, number]> = {
  h: [KEY_STEP, 0],
  l: [-KEY_STEP, 0],
  k: [0, KEY_STEP],
  j: [0, -KEY_STEP],
};
/** a "zoom to area" drag smaller than this (px, either side) is a click and zooms nowhere */
const AREA_MIN_PX = 4;

export class MapController {
  readonly toolbar: HTMLElement;
  private camera: Camera = { cx: 0, cy: 0, scale: 0.05, width: 800, height: 600 };
  private current: Tool = "pan";
  private fitted = false;
  private drag: Drag | null = null;
  private dragArea: Area | null = null;
  private target: Pose | null = null;
  private shadow: Pose | null = null;
  private readonly toolButtons = new Map<Tool, HTMLButtonElement>();

  constructor(
    private readonly canvas: HTMLCanvasElement,
    private readonly session: PlatformSession,
    private readonly shown: Shown,
    private readonly say: (text: string) => void,
    private readonly invalidate: () => void,
  ) {
    this.toolbar = this.makeToolbar();
    this.listen();
  }

  /** the camera of the next frame */
  get cam(): Camera {
    return this.camera;
  }

  get tool(): Tool {
    return this.current;
  }

  /** the target flag (shown in the tool "flag") */
  get flag(): Pose | null {
    return this.target;
  }

  /** where a drag of the tool "shift" would put the platform */
  get ghost(): Pose | null {
    return this.shadow;
  }

  /** the rectangle of a "zoom to area" drag */
  get area(): Readonly<Area> | null {
    return this.dragArea;
  }

  /** Has the view been fitted to a map once (the first map is shown whole)? */
  get hasFitted(): boolean {
    return this.fitted;
  }

  private makeToolbar(): HTMLElement {
    const toolbar = h("div", { role: "toolbar", class: "map-tools" });
    bind(toolbar, "map.tools", { text: false });
    const act = (key: Key, fn: () => void, shortcut = "") => {
      const svg = icon(key);
      const b = h("button", {
        type: "button",
        class: svg === null ? "" : "icon-button",
        "aria-keyshortcuts": shortcut || false,
      });
      // issue 35: an icon with the tool's name as its accessible name and the guide's words (5.3) as its tooltip
      bind(b, key, { text: svg === null, title: MAP_TIPS[key] });
      if (svg !== null) {
        b.append(svg);
      }
      b.addEventListener("click", fn);
      toolbar.append(b);
      return b;
    };
    act("map.refresh", () => this.session.refreshDocuments(), "R");
    act("map.zoomAll", () => this.zoomAll());
    act("map.zoomIn", () => this.zoom(1.5), "+");
    act("map.zoomOut", () => this.zoom(1 / 1.5), "-");
    const tools: Array<[Tool, Key]> = [
      ["zoomArea", "map.zoomArea"],
      ["pan", "map.pan"],
      ["shift", "map.shift"],
      ["flag", "map.flag"],
    ];
    for (const [tool, key] of tools) {
      const b = act(key, () => this.setTool(this.current === tool ? "pan" : tool));
      b.setAttribute("aria-pressed", String(tool === this.current));
      this.toolButtons.set(tool, b);
    }
    // issue 33: shifting the platform and the target flag send commands: only while this tab may command
    guard(this.session, this.toolButtons.get("shift")!);
    guard(this.session, this.toolButtons.get("flag")!);
    return toolbar;
  }

  private listen(): void {
    const c = this.canvas;
    new ResizeObserver(() => this.resize()).observe(c);
    c.addEventListener(
      "wheel",
      (e) => {
        e.preventDefault();
        this.zoom(e.deltaY < 0 ? 1.2 : 1 / 1.2, e.offsetX, e.offsetY);
      },
      { passive: false },
    );
    c.addEventListener("pointerdown", (e) => this.down(e));
    c.addEventListener("pointermove", (e) => this.move(e));
    c.addEventListener("pointerup", (e) => this.up(e));
    c.addEventListener("contextmenu", (e) => e.preventDefault());
    // issue 35: the map tools' keys on the focused map (their aria-keyshortcuts; ui/icons.ts SHORTCUTS). Zoom all
    // has none: A drives left in motion mode Velocity (panels/motion.ts)
    const keyActions: Record<string, () => void> = {
      r: () => this.session.refreshDocuments(),
      "+": () => this.zoom(1.5),
      "-": () => this.zoom(1 / 1.5),
    };
    c.addEventListener("keydown", (e) => {
      const m = KEY_MOVES[e.key];
      if (m !== undefined) {
        this.setCamera(panBy(this.camera, m[0], m[1]));
      }
      if (!e.ctrlKey && !e.metaKey && !e.altKey) {
        keyActions[e.key.toLowerCase()]?.();
      }
    });
  }

  setCamera(cam: Camera): void {
    this.camera = cam;
    this.invalidate();
  }

  /** Centre on a point without asking for a frame (the caller asks: the view centres on the platform). */
  centreOn(x: number, y: number): void {
    this.camera = { ...this.camera, cx: x, cy: y };
  }

  zoomAll(): void {
    const b = this.shown.bounds;
    if (b && this.camera.width > 1) {
      this.camera = fit(this.camera, b);
      this.fitted = true;
    }
    this.invalidate();
  }

  zoom(factor: number, sx = this.camera.width / 2, sy = this.camera.height / 2): void {
    this.setCamera(zoomAt(this.camera, factor, sx, sy));
  }

  setTool(tool: Tool): void {
    this.current = tool;
    for (const [k, b] of this.toolButtons) {
      b.setAttribute("aria-pressed", String(k === tool));
    }
    if (tool === "flag" && this.target === null) {
      const st = this.shown.status;
      this.target = st
        ? { x: st.estX, y: st.estY, angle: st.estAngle / 1000 }
        : { x: this.camera.cx, y: this.camera.cy, angle: 0 };
    }
    this.canvas.dataset.tool = tool;
    this.invalidate();
  }

  private resize(): void {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    this.canvas.width = Math.max(1, Math.round(r.width * dpr));
    this.canvas.height = Math.max(1, Math.round(r.height * dpr));
    this.camera = { ...this.camera, width: r.width, height: r.height };
    if (!this.fitted && this.shown.bounds) {
      this.zoomAll();
    }
    this.invalidate();
  }

  // ---- pointer tools
  private down(e: PointerEvent): void {
    this.canvas.setPointerCapture(e.pointerId);
    this.canvas.focus();
    this.drag = { x: e.offsetX, y: e.offsetY, button: e.button, cam: this.camera };
    const hooks = this.shown.hooks;
    if (this.current === "edit" && hooks !== null) {
      const [wx, wy] = toWorld(this.camera, e.offsetX, e.offsetY);
      hooks.down(wx, wy, this.camera.scale, e.button);
      return;
    }
    const st = this.shown.status;
    if (this.current === "shift" && st) {
      this.drag.pose = { x: st.estX, y: st.estY, angle: st.estAngle / 1000 };
    } else if (this.current === "flag" && this.target) {
      this.drag.pose = { ...this.target };
    } else if (this.current === "zoomArea") {
      this.dragArea = { x0: e.offsetX, y0: e.offsetY, x1: e.offsetX, y1: e.offsetY };
    }
  }

  private dragged(e: PointerEvent, d = this.drag): Pose | null {
    return d?.pose === undefined ? null : draggedPose({ ...d, pose: d.pose }, this.camera, e.offsetX, e.offsetY);
  }

  private move(e: PointerEvent): void {
    const d = this.drag;
    if (d === null) {
      return;
    }
    const hooks = this.shown.hooks;
    const tool = this.current;
    if (tool === "edit" && hooks !== null) {
      const [wx, wy] = toWorld(this.camera, e.offsetX, e.offsetY);
      hooks.move(wx, wy);
      this.invalidate();
      return;
    }
    if (tool === "pan" || ((tool === "shift" || tool === "flag") && d.pose === undefined)) {
      this.setCamera(panBy(d.cam, e.offsetX - d.x, e.offsetY - d.y));
    } else if (tool === "zoomArea" && this.dragArea) {
      this.dragArea.x1 = e.offsetX;
      this.dragArea.y1 = e.offsetY;
      this.invalidate();
    } else if (tool === "flag") {
      this.target = this.dragged(e);
      this.invalidate();
    } else if (tool === "shift") {
      this.shadow = this.dragged(e);
      this.invalidate();
    }
  }

  private up(e: PointerEvent): void {
    const d = this.drag;
    this.drag = null;
    if (d === null) {
      return;
    }
    const hooks = this.shown.hooks;
    if (this.current === "edit" && hooks !== null) {
      const [wx, wy] = toWorld(this.camera, e.offsetX, e.offsetY);
      hooks.up(wx, wy);
      this.invalidate();
      return;
    }
    if (this.current === "zoomArea" && this.dragArea) {
      this.zoomToArea(this.dragArea);
      this.dragArea = null;
      this.invalidate();
      return;
    }
    const pose = this.dragged(e, d);
    if (pose === null) {
      return;
    }
    if (this.current === "shift") {
      this.shadow = null;
      // guide 5.3: "The platform can be shifted by drag and drop. The frame is rotated with a right-click."
      this.send(
        new SetFrmPltfRequest({ x: pose.x, y: pose.y, angle: Math.round(pose.angle * 1000) }),
        "map.sentShift",
        pose,
      );
    } else if (this.current === "flag") {
      this.target = pose;
      this.sendFlag();
    }
    this.invalidate();
  }

  private zoomToArea(a: Area): void {
    if (Math.abs(a.x1 - a.x0) > AREA_MIN_PX && Math.abs(a.y1 - a.y0) > AREA_MIN_PX) {
      const [x0, y0] = toWorld(this.camera, Math.min(a.x0, a.x1), Math.max(a.y0, a.y1));
      const [x1, y1] = toWorld(this.camera, Math.max(a.x0, a.x1), Math.min(a.y0, a.y1));
      this.setCamera(fit(this.camera, { minX: x0, minY: y0, maxX: x1, maxY: y1 }, 0));
    }
  }

  /** guide 5.3: "Used in motion mode Automatic, the platform will move to a specified location." */
  sendFlag(): void {
    const f = this.target;
    if (f === null) {
      return;
    }
    if (this.shown.status?.motionMode !== MotionMode.MODE_MOTION_AUTOMATIC) {
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
}
