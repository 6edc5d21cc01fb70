/**
 * Typed coordinates of a selected map object (issue 20 "typed coordinates for a selected object (mm and
 * degrees)"): the fields shown for an object and the object's new geometry from what the user typed.
 *
 * Fields: x1, y1, x2, y2, ... (mm) for every point; r (mm) for a circle; text for a label; for a two-point object
 * (a line of any kind, a reflector) also its length (mm) and direction (degrees, counter-clockwise from +x, from
 * the first point to the second). A changed length or direction wins over the second point's typed x2/y2: the
 * first point stays and the second is placed from it. Pure: strings in, a result or the reason out.
 */
import type { MapObject } from "../scene/map";
import { clean, EPS, type Result } from "./geometry";
import { MAX_MM, POLYGON_KINDS, type PolygonKind, signedArea2 } from "./shapes";

export type Fields = Record<string, string>;

export interface Geometry {
  points: number[];
  r?: number;
  text?: string;
}

const round3 = (v: number): number => {
  const k = Math.round(v * 1000) / 1000;
  return k === 0 ? 0 : k;
};

const isTwoPoint = (o: MapObject): boolean => o.points.length === 4 && o.kind !== "workarea" && o.kind !== "prohibit";

/** The fields shown for `o`, in display order. */
export function fieldsOf(o: MapObject): Fields {
  const f: Fields = {};
  for (let i = 0; i + 1 < o.points.length; i += 2) {
    f[`x${i / 2 + 1}`] = String(o.points[i]);
    f[`y${i / 2 + 1}`] = String(o.points[i + 1]);
  }
  if (o.r !== undefined) {
    f.r = String(o.r);
  }
  if (o.kind === "hiddenlabel") {
    f.text = o.text ?? o.attrs.text ?? "";
  }
  if (isTwoPoint(o)) {
    const [x0, y0, x1, y1] = o.points;
    f.length = String(round3(Math.hypot(x1 - x0, y1 - y0)));
    f.direction = String(round3((Math.atan2(y1 - y0, x1 - x0) * 180) / Math.PI));
  }
  return f;
}

function number(input: Fields, key: string, what: string): Result<number> {
  const raw = (input[key] ?? "").trim();
  const v = raw === "" ? Number.NaN : Number(raw);
  if (!Number.isFinite(v)) {
    return { ok: false, reason: `${what} is not a number: ${JSON.stringify(raw)}` };
  }
  if (Math.abs(v) > MAX_MM) {
    return { ok: false, reason: `${what} ${v} is outside the map's range (±${MAX_MM} mm)` };
  }
  return { ok: true, value: v };
}

function pointsFrom(o: MapObject, input: Fields): Result<number[]> {
  const out: number[] = [];
  for (let k = 1; 2 * k <= o.points.length; k++) {
    for (const axis of ["x", "y"]) {
      const v = number(input, `${axis}${k}`, `${axis.toUpperCase()}${k} (mm)`);
      if (!v.ok) {
        return v;
      }
      out.push(v.value);
    }
  }
  return { ok: true, value: out };
}

/** The second point placed from the first by a typed length (mm) and direction (degrees). */
function polar(points: number[], input: Fields): Result<number[]> {
  const len = number(input, "length", "the length (mm)");
  if (!len.ok) {
    return len;
  }
  const dir = number(input, "direction", "the direction (degrees)");
  if (!dir.ok) {
    return dir;
  }
  if (len.value <= 0) {
    return { ok: false, reason: "the length must be more than 0 mm" };
  }
  const a = (dir.value * Math.PI) / 180;
  const [x0, y0] = points;
  return { ok: true, value: [x0, y0, clean(x0 + len.value * Math.cos(a)), clean(y0 + len.value * Math.sin(a))] };
}

function checkShape(o: MapObject, g: Geometry): string | null {
  const p = g.points;
  if (isTwoPoint(o) && Math.hypot(p[2] - p[0], p[3] - p[1]) < EPS) {
    return `the ${o.kind} would have zero length`;
  }
  if (POLYGON_KINDS.includes(o.kind as PolygonKind) && Math.abs(signedArea2(p)) < EPS) {
    return "the polygon would have no area: its vertices lie on one line";
  }
  if (o.kind === "circle" && !((g.r ?? 0) > 0)) {
    return "the radius must be more than 0 mm";
  }
  if (o.kind === "hiddenlabel" && (g.text ?? "") === "") {
    return "a label needs a text";
  }
  return null;
}

/**
 * The new geometry of `o` from the typed `input`, given the fields that were `shown` (to see what changed).
 * Unchanged fields give the object's own values back exactly.
 */
export function applyFields(o: MapObject, shown: Fields, input: Fields): Result<Geometry> {
  const pts = pointsFrom(o, input);
  if (!pts.ok) {
    return pts;
  }
  let points = pts.value.map(clean);
  if (isTwoPoint(o) && (input.length !== shown.length || input.direction !== shown.direction)) {
    const p = polar(points, input);
    if (!p.ok) {
      return p;
    }
    points = p.value;
  }
  const g: Geometry = { points };
  if (o.r !== undefined) {
    const r = number(input, "r", "the radius (mm)");
    if (!r.ok) {
      return r;
    }
    g.r = r.value;
  }
  if (o.kind === "hiddenlabel") {
    g.text = (input.text ?? "").trim();
  }
  const bad = checkShape(o, g);
  return bad === null ? { ok: true, value: g } : { ok: false, reason: bad };
}
