/**
 * The map editor's document (guide 5.4; format guide 6.5 "Map"): the scene the view draws (scene/map.ts) plus
 * what the scene does not model, so that a document read and written back is the same element for element:
 * the root's and the layers' attributes, elements outside the layers, and each object's unknown children
 * (`extra`). An element kind the editor does not know is an object of that kind, kept and written back.
 */
import { readMapFast } from "./mapfast";
import type { EditorObject, MapDoc, RootEntry } from "./mapmodel";
import { elementsOf, parseXml, writeDocument, type XmlElement, XmlError } from "./xml";

export type { EditorObject, MapDoc, RootEntry } from "./mapmodel";

export class MapDocError extends Error {}

const POINT_TAGS = new Set(["point", "center"]);

function num(el: XmlElement, name: string, owner: string): number {
  const raw = el.attrs.find(([k]) => k === name)?.[1];
  const v = raw === undefined || raw.trim() === "" ? Number.NaN : Number(raw);
  if (!Number.isFinite(v)) {
    throw new MapDocError(`<${owner}> has a <${el.name}> without a number in ${name}`);
  }
  return v;
}

function toObject(el: XmlElement, id: number, layer: number): EditorObject {
  const points: number[] = [];
  const extra: XmlElement[] = [];
  let r: number | undefined;
  for (const c of elementsOf(el)) {
    if (POINT_TAGS.has(c.name)) {
      points.push(num(c, "x", el.name), num(c, "y", el.name));
    } else if (c.name === "radius" && r === undefined) {
      r = num(c, "r", el.name);
    } else {
      extra.push(c);
    }
  }
  const obj: EditorObject = { id, kind: el.name, layer, points, attrs: Object.fromEntries(el.attrs) };
  if (r !== undefined) {
    obj.r = r;
  }
  if (el.name === "hiddenlabel") {
    obj.text = obj.attrs.text ?? "";
  }
  if (extra.length > 0) {
    obj.extra = extra;
  }
  return obj;
}

/**
 * Read a map document; MapDocError (one line) when it is not well-formed or not a map. The platform's usual form
 * goes through the fast reader (mapfast.ts); whatever it does not take, the general reader below.
 */
export function parseMapDoc(src: string, name = ""): MapDoc {
  return readMapFast(src, name) ?? parseMapDocXml(src, name);
}

/** The general reader: the XML tree first (xml.ts), then the objects. */
export function parseMapDocXml(src: string, name = ""): MapDoc {
  let root: XmlElement;
  try {
    root = parseXml(src);
  } catch (e) {
    throw new MapDocError(`the map is not well-formed XML: ${(e as Error).message}`);
  }
  if (root.name !== "map") {
    throw new MapDocError(`expected a <map> document, got <${root.name}>`);
  }
  const objects: EditorObject[] = [];
  const entries: RootEntry[] = [];
  for (const el of elementsOf(root)) {
    if (el.name !== "layer") {
      entries.push({ kept: el });
      continue;
    }
    const index = Number(el.attrs.find(([k]) => k === "index")?.[1] ?? "0");
    if (!Number.isInteger(index)) {
      throw new MapDocError(`a <layer> has an index that is not an integer`);
    }
    entries.push({ layer: index, attrs: el.attrs });
    for (const child of elementsOf(el)) {
      objects.push(toObject(child, objects.length, index));
    }
  }
  const version = root.attrs.find(([k]) => k === "Version" || k === "version")?.[1] ?? null;
  return { scene: { name, version, objects }, rootAttrs: root.attrs, entries, nextId: objects.length };
}

const fmt = (v: number): string => String(v);

function fromObject(o: EditorObject): XmlElement {
  const attrs = Object.entries(o.attrs);
  if (o.kind === "hiddenlabel" && o.text !== undefined) {
    const k = attrs.findIndex(([n]) => n === "text");
    if (k >= 0) {
      attrs[k] = ["text", o.text];
    } else {
      attrs.push(["text", o.text]);
    }
  }
  const tag = o.kind === "circle" ? "center" : "point";
  const children: XmlElement[] = [];
  for (let i = 0; i + 1 < o.points.length; i += 2) {
    children.push({
      type: "element",
      name: tag,
      attrs: [
        ["x", fmt(o.points[i])],
        ["y", fmt(o.points[i + 1])],
      ],
      children: [],
    });
  }
  if (o.r !== undefined) {
    children.push({ type: "element", name: "radius", attrs: [["r", fmt(o.r)]], children: [] });
  }
  return { type: "element", name: o.kind, attrs, children: [...children, ...(o.extra ?? [])] };
}

/** The document as XML elements: layers in their first order, a layer new to the document at the end. */
export function mapDocToXml(doc: MapDoc): XmlElement {
  const byLayer = new Map<number, XmlElement[]>();
  for (const o of doc.scene.objects as EditorObject[]) {
    const list = byLayer.get(o.layer) ?? [];
    list.push(fromObject(o));
    byLayer.set(o.layer, list);
  }
  const children: XmlElement[] = [];
  const seen = new Set<number>();
  const layer = (index: number, attrs: Array<[string, string]>): XmlElement => ({
    type: "element",
    name: "layer",
    attrs,
    children: byLayer.get(index) ?? [],
  });
  for (const e of doc.entries) {
    if ("kept" in e) {
      children.push(e.kept);
    } else if (!seen.has(e.layer)) {
      seen.add(e.layer);
      children.push(layer(e.layer, e.attrs));
    }
  }
  for (const index of [...byLayer.keys()].filter((k) => !seen.has(k)).sort((a, b) => a - b)) {
    children.push(layer(index, [["index", String(index)]]));
  }
  return { type: "element", name: "map", attrs: doc.rootAttrs, children };
}

export function writeMapDoc(doc: MapDoc): string {
  return writeDocument(mapDocToXml(doc));
}

/** A new, empty map. */
export function newMapDoc(name = ""): MapDoc {
  return { scene: { name, version: "1.0", objects: [] }, rootAttrs: [["Version", "1.0"]], entries: [], nextId: 0 };
}

/**
 * Whether two map documents hold the same objects (kind, layer, points, radius, text, attributes, in order):
 * after CMD_SET_MAP, which has no reply, the platform's GET_MAP says whether it took the map. A document that does
 * not parse is never the same.
 */
export function sameObjects(a: string, b: string): boolean {
  const key = (src: string): string | null => {
    try {
      return JSON.stringify(
        parseMapDoc(src).scene.objects.map((o: EditorObject) => [
          o.kind,
          o.layer,
          o.points,
          o.r ?? null,
          o.text ?? null,
          o.attrs,
        ]),
      );
    } catch {
      return null;
    }
  };
  const ka = key(a);
  return ka !== null && ka === key(b);
}

export { XmlError };
