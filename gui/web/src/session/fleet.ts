/**
 * The fleet (issue 30: `pltf gui --target A --target B ...` or `--fleet FILE`): which platforms the page shows,
 * their colours and names, which one is selected, what each status line says, and which body a click on the map
 * hits. Pure functions and plain data; the sessions and the list live in panels/fleet.ts.
 *
 * Rules:
 * - The page's address lists the platforms (`?target=A&target=B...`, as `pltf gui` prints it); the first is
 *   selected at first, `?selected=HOST:PORT` selects another. One target (or none) is no fleet: the page is the
 *   single-platform GUI it always was.
 * - A name comes from the gateway (`GET /api/targets`: the fleet file's names); without one the address names it.
 * - Colours are a fixed table, taken in the order of the address (the same platform, the same colour, on every
 *   reload); past its end they repeat.
 * - Only the selected platform is commanded: the one session the panels hold is switched to it
 *   (`PlatformSession.open(target)`), the others are only watched (GET_STATUS). Guide 5.2: "To connect the GUI to
 *   the platform select the desired server in the server combo box." - one platform commanded at a time, as the
 *   guide's GUI switches server (erratum E-GUI-008).
 * - One GET_STATUS stream per platform: the selected one's status line and body read the panels' session (20 Hz);
 *   its watcher stops polling while it is selected and starts again when another is.
 * - Each body has its own footprint (guide 5.9 Geometry: PltfLength, DistWheels, DistPltfCenterToWheelAxis), from
 *   its own platform's GET_PLTF_PARAM_VEC; until that is known, the map's default one.
 * - An open editor's document belongs to the platform it was loaded from (or sent to), and survives a switch
 *   (erratum E-GUI-012): `DocumentOwner` below.
 */
import type { GetStatusReply } from "../pltf";
import { DEFAULT_FOOTPRINT, type Footprint } from "../view/overlay";

/** Distinct on the map's white and grey (Okabe-Ito, without yellow): blue, vermilion, green, purple, ... */
export const FLEET_COLOURS = ["#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000"];

export interface FleetMember {
  target: string;
  name: string;
  colour: string;
}

/** What the map draws of one platform: its pose (mm, mm, degrees) when known. */
export interface FleetBody {
  name: string;
  target: string;
  colour: string;
  selected: boolean;
  pose: { x: number; y: number; angle: number } | null;
  /** its own outline (its parameters); null until they are read */
  footprint: Footprint | null;
}

/** The radius (mm) of the circle around a footprint's centre that holds it (a click within it hits the body). */
export function reach(f: Footprint): number {
  return Math.hypot(Math.max(Math.abs(f.rear), Math.abs(f.front)), f.halfWidth);
}

/** The platforms the address lists, in order, each once; [] when it lists fewer than two (no fleet). */
export function fleetTargets(params: URLSearchParams): string[] {
  const targets = [...new Set(params.getAll("target").filter((t) => t !== ""))];
  return targets.length > 1 ? targets : [];
}

/** The platform selected at first: `?selected=` when it is one of them, else the first. */
export function firstSelected(targets: string[], params: URLSearchParams): string {
  const wanted = params.get("selected");
  return wanted !== null && targets.includes(wanted) ? wanted : (targets[0] ?? "");
}

/** The members: names from the gateway's fleet (`/api/targets`), else the address; colours in order. */
export function fleetMembers(targets: string[], named: Array<{ name: string; target: string }> = []): FleetMember[] {
  const names = new Map(named.map((n) => [n.target, n.name]));
  return targets.map((target, i) => ({
    target,
    name: names.get(target) ?? target,
    colour: FLEET_COLOURS[i % FLEET_COLOURS.length],
  }));
}

/** The parts of a status line (guide 6.4 CMD_GET_STATUS): worded by the panel, read as data by the tests. */
export interface StatusLine {
  name: string;
  connected: boolean;
  operationState: number | null;
  motionMode: number | null;
  /** x mm, y mm, degrees */
  pose: [number, number, number] | null;
}

export function statusLine(name: string, connected: boolean, s: GetStatusReply | null): StatusLine {
  if (!connected || s === null) {
    return { name, connected, operationState: null, motionMode: null, pose: null };
  }
  return {
    name,
    connected,
    operationState: s.operationState,
    motionMode: s.motionMode,
    pose: [s.estX, s.estY, s.estAngle / 1000],
  };
}

/**
 * The body under a world point (mm): the nearest whose centre lies within its own footprint's reach (`radius` mm
 * for a body whose footprint is not known yet; a tie: the first), or null.
 */
export function bodyAt(bodies: FleetBody[], x: number, y: number, radius: number): FleetBody | null {
  let best: FleetBody | null = null;
  let bestD = Number.POSITIVE_INFINITY;
  for (const b of bodies) {
    if (b.pose === null) {
      continue;
    }
    const d = Math.hypot(b.pose.x - x, b.pose.y - y);
    if (d > (b.footprint === null ? radius : reach(b.footprint))) {
      continue;
    }
    if (d < bestD) {
      best = b;
      bestD = d;
    }
  }
  return best;
}

/** A body's footprint as drawn: its own; until it is read, `session`'s (the panels' session's parameters) for the
 * selected one and the default for the others - never the selected platform's: it is another platform. */
export function drawnFootprint(b: FleetBody, session: Footprint): Footprint {
  return b.footprint ?? (b.selected ? session : DEFAULT_FOOTPRINT);
}

/**
 * The canvas's `data-fleet`: one `name@x,y,angle/rear,front,halfWidth` per body (mm, degrees; the footprint as
 * drawn, `drawnWith` the body; `name@-`: pose unknown, not drawn), `*` before the selected.
 */
export function fleetData(bodies: FleetBody[], drawnWith: (b: FleetBody) => Footprint): string {
  return bodies
    .map((b) => {
      if (b.pose === null) {
        return `${b.selected ? "*" : ""}${b.name}@-`;
      }
      const f = drawnWith(b);
      const at = `${Math.round(b.pose.x)},${Math.round(b.pose.y)},${b.pose.angle.toFixed(1)}`;
      const outline = `${Math.round(f.rear)},${Math.round(f.front)},${Math.round(f.halfWidth)}`;
      return `${b.selected ? "*" : ""}${b.name}@${at}/${outline}`;
    })
    .join(";");
}

/** The page's address with the platform `target` selected (kept over a reload). */
export function selectedHref(href: string, target: string): string {
  const url = new URL(href);
  url.searchParams.set("selected", target);
  return url.href;
}

/**
 * Whose document an editor holds (erratum E-GUI-012): the platform selected when it came into the editor (loaded
 * from it, opened from a file or started new) or was last sent to. A switch of the selected platform leaves the
 * document, its history and its owner alone; sending it elsewhere asks first (panels/fleet.ts) and makes the
 * platform it went to its owner.
 */
export class DocumentOwner {
  private owner: string;

  /** `selected`: the platform selected now (its target) */
  constructor(private readonly selected: () => string) {
    this.owner = selected();
  }

  /** The document is now the selected platform's. */
  take(): void {
    this.owner = this.selected();
  }

  /** The target of the platform the document belongs to. */
  get platform(): string {
    return this.owner;
  }

  /** Another platform than the document's is selected: a Send would go there. */
  get elsewhere(): boolean {
    return this.owner !== this.selected();
  }
}
