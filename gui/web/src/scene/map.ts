/**
 * The map document (guide 6.5 "Map") as plain data: what GET_MAP returns, what the map view draws, and what the
 * map editor (guide 5.4, next issue) will edit through commands. Nothing here draws or sends.
 *
 * Every child of a <layer> is one object, in document order, with its kind (the element name), its points in mm,
 * a circle's radius, a label's text and the element's other attributes kept as they were (`attrs`), so a
 * document read and written back keeps what this model does not know.
 */

export const LINE_KINDS = ["line", "auxline", "linemapped", "auxlinemapped", "reflmark"] as const;
export const AREA_KINDS = ["workarea", "prohibit", "hiddenpolygon"] as const;
export const KINDS = [...LINE_KINDS, "circle", ...AREA_KINDS, "hiddenlabel"] as const;
export type Kind = (typeof KINDS)[number];

export interface MapObject {
  id: number;
  kind: string; // a Kind, or an element this model does not know (kept, not drawn)
  layer: number;
  /** x0, y0, x1, y1, ... in mm */
  points: number[];
  r?: number;
  text?: string;
  attrs: Record<string, string>;
}

export interface MapScene {
  name: string;
  version: string | null;
  objects: MapObject[];
}

export class MapParseError extends Error {}

function num(el: Element, name: string): number {
  const v = Number(el.getAttribute(name));
  if (!Number.isFinite(v)) {
    throw new MapParseError(`<${el.tagName}> has no number in ${name}`);
  }
  return v;
}

/** Parse map XML (DOMParser); MapParseError with a one-line reason when it is not a map. */
export function parseMap(xml: string, name = ""): MapScene {
  if (xml.trim() === "") {
    return { name, version: null, objects: [] };
  }
  const doc = new DOMParser().parseFromString(xml, "application/xml");
  const err = doc.getElementsByTagName("parsererror")[0];
  if (err !== undefined) {
    throw new MapParseError(`the map is not well-formed XML: ${(err.textContent ?? "").split("\n")[0]}`);
  }
  const root = doc.documentElement;
  if (root.tagName !== "map") {
    throw new MapParseError(`expected a <map> document, got <${root.tagName}>`);
  }
  const objects: MapObject[] = [];
  let id = 0;
  for (const layer of Array.from(root.children)) {
    if (layer.tagName !== "layer") {
      continue;
    }
    const index = Number(layer.getAttribute("index") ?? "0");
    for (const el of Array.from(layer.children)) {
      const points: number[] = [];
      let r: number | undefined;
      for (const child of Array.from(el.children)) {
        if (child.tagName === "point" || child.tagName === "center") {
          points.push(num(child, "x"), num(child, "y"));
        } else if (child.tagName === "radius") {
          r = num(child, "r");
        }
      }
      const attrs: Record<string, string> = {};
      for (const a of Array.from(el.attributes)) {
        attrs[a.name] = a.value;
      }
      const obj: MapObject = { id: id++, kind: el.tagName, layer: index, points, attrs };
      if (r !== undefined) {
        obj.r = r;
      }
      if (el.tagName === "hiddenlabel") {
        obj.text = el.getAttribute("text") ?? (el.textContent ?? "").trim();
      }
      objects.push(obj);
    }
  }
  return { name, version: root.getAttribute("Version") ?? root.getAttribute("version"), objects };
}

/** Objects per kind (the counts the map view exposes). */
export function countKinds(scene: MapScene): Record<string, number> {
  const out: Record<string, number> = {};
  for (const k of KINDS) {
    out[k] = 0;
  }
  for (const o of scene.objects) {
    out[o.kind] = (out[o.kind] ?? 0) + 1;
  }
  return out;
}

export interface Bounds {
  minX: number;
  minY: number;
  maxX: number;
  maxY: number;
}

export function sceneBounds(scene: MapScene): Bounds | null {
  let b: Bounds | null = null;
  for (const o of scene.objects) {
    const r = o.r ?? 0;
    for (let i = 0; i + 1 < o.points.length; i += 2) {
      const x = o.points[i];
      const y = o.points[i + 1];
      b = b === null ? { minX: x - r, minY: y - r, maxX: x + r, maxY: y + r } : b;
      b.minX = Math.min(b.minX, x - r);
      b.minY = Math.min(b.minY, y - r);
      b.maxX = Math.max(b.maxX, x + r);
      b.maxY = Math.max(b.maxY, y + r);
    }
  }
  return b;
}
