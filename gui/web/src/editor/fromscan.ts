/**
 * guide 5.4 "Convert line from scan": the platform's current laser scan (CMD_GET_STATUS "Observed scan (platform
 * coordinates)", guide 6.4) put into the map's frame with the estimated pose, and line segments fitted to it
 * (scanfit.ts, erratum E-GUI-004) with the platform's MinLineLenAux and MinLineLenMap (guide 5.9 Mapping).
 */
import type { MapObject } from "../scene/map";
import { clean, type Pt } from "./geometry";
import { fitScan } from "./scanfit";

/** What the conversion reads of a GET_STATUS reply. */
export interface ScanStatus {
  estX: number;
  estY: number;
  /** 1/1000 degree */
  estAngle: number;
  scan: ReadonlyArray<{ x: number; y: number }>;
}

/** guide 5.9 Mapping defaults (spec/parameters.yaml), used when the platform's parameters are not known yet. */
export const LINE_LEN_DEFAULTS = { MinLineLenAux: 200, MinLineLenMap: 500 };

/** The scan's points in the map's frame (mm), in scan order. */
export function scanToWorld(s: ScanStatus): Pt[] {
  const a = (s.estAngle / 1000) * (Math.PI / 180);
  const [c, n] = [Math.cos(a), Math.sin(a)];
  return s.scan.map((p) => ({ x: s.estX + p.x * c - p.y * n, y: s.estY + p.x * n + p.y * c }));
}

/**
 * The map objects, in `layer`, for the lines fitted to the scan; `lens` are MinLineLenAux and MinLineLenMap in mm.
 */
export function linesFromScan(
  s: ScanStatus,
  lens: { MinLineLenAux: number; MinLineLenMap: number },
  layer = 0,
): Array<Omit<MapObject, "id">> {
  const origin = { x: s.estX, y: s.estY };
  const lines = fitScan(scanToWorld(s), {
    origin,
    minLineLenAux: lens.MinLineLenAux,
    minLineLenMap: lens.MinLineLenMap,
  });
  return lines.map((l) => ({
    kind: l.kind,
    layer,
    points: [l.a.x, l.a.y, l.b.x, l.b.y].map((v) => clean(Math.round(v))),
    attrs: {},
  }));
}
