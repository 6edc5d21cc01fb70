/**
 * The view transform of the map: world mm (x right, y up, as the platform's frame) <-> canvas pixels (y down).
 * Pure arithmetic, unit-tested; the map view owns one camera and changes it only through these functions.
 */
import type { Bounds } from "../scene/map";

export interface Camera {
  /** world point at the canvas centre, mm */
  cx: number;
  cy: number;
  /** pixels per mm */
  scale: number;
  /** canvas size in CSS pixels */
  width: number;
  height: number;
}

export const MIN_SCALE = 1e-4; // 10 km per pixel
export const MAX_SCALE = 2; // 0.5 mm per pixel

export function toScreen(c: Camera, x: number, y: number): [number, number] {
  return [(x - c.cx) * c.scale + c.width / 2, (c.cy - y) * c.scale + c.height / 2];
}

export function toWorld(c: Camera, sx: number, sy: number): [number, number] {
  return [(sx - c.width / 2) / c.scale + c.cx, c.cy - (sy - c.height / 2) / c.scale];
}

/** The world rectangle the canvas shows. */
export function viewBounds(c: Camera): Bounds {
  const hw = c.width / 2 / c.scale;
  const hh = c.height / 2 / c.scale;
  return { minX: c.cx - hw, minY: c.cy - hh, maxX: c.cx + hw, maxY: c.cy + hh };
}

/** Pan by a screen displacement (drag). */
export function panBy(c: Camera, dx: number, dy: number): Camera {
  return { ...c, cx: c.cx - dx / c.scale, cy: c.cy + dy / c.scale };
}

/** Zoom by `factor` keeping the world point under screen point (sx, sy) fixed. */
export function zoomAt(c: Camera, factor: number, sx: number, sy: number): Camera {
  const scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, c.scale * factor));
  const [wx, wy] = toWorld(c, sx, sy);
  const next = { ...c, scale };
  const [nx, ny] = toWorld(next, sx, sy);
  return { ...next, cx: next.cx + (wx - nx), cy: next.cy + (wy - ny) };
}

/** Show `b` whole with a margin (zoom all, zoom to a selected area). */
export function fit(c: Camera, b: Bounds, margin = 0.05): Camera {
  const w = Math.max(b.maxX - b.minX, 1);
  const h = Math.max(b.maxY - b.minY, 1);
  const scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, Math.min(c.width / w, c.height / h) * (1 - 2 * margin)));
  return { ...c, cx: (b.minX + b.maxX) / 2, cy: (b.minY + b.maxY) / 2, scale };
}
