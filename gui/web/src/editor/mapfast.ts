/**
 * The map editor's fast reader (issue 20: a map of 50,000 lines loaded and drawn within a second). It reads the
 * form a platform writes (guide 6.5 "Map": a <map> of <layer>s whose objects have self-closing <point>, <center>
 * and <radius> children) straight into the editor's objects, without the XML tree `parseXml` builds first (one
 * element, an attribute list and a children list per point: a million allocations on 50,000 lines).
 *
 * It gives up (null) wherever a document leaves that form: a comment, text, an entity, a nested child, an
 * element beside the layers, a bad number, anything malformed. The caller (mapdoc.ts `parseMapDoc`) then reads
 * the document with the general reader, so the result, or the one-line error, is always the general reader's.
 * Unknown attributes and unknown self-closing children of an object are kept as the general reader keeps them.
 */
import type { EditorObject, MapDoc, RootEntry } from "./mapdoc";
import { MAX_XML_CHARS, type XmlElement } from "./xml";

const isSpace = (c: number): boolean => c === 32 || c === 10 || c === 13 || c === 9;
/** [A-Za-z_:] */
const isNameStart = (c: number): boolean => (c >= 97 && c <= 122) || (c >= 65 && c <= 90) || c === 95 || c === 58;
/** [-A-Za-z0-9_:.] */
const isNameChar = (c: number): boolean => isNameStart(c) || (c >= 48 && c <= 57) || c === 45 || c === 46;

interface Tag {
  name: string;
  attrs: Array<[string, string]>;
  end: number;
  self: boolean;
}

/** ASCII whitespace from `i` (other white space stops here, and the general reader takes the document). */
function ws(src: string, i: number): number {
  let j = i;
  while (isSpace(src.charCodeAt(j))) {
    j++;
  }
  return j;
}

/**
 * Whitespace, comments and processing instructions from `i` (the general reader drops them all where this reader
 * goes: around the root, between layers, objects and points); past the end when one is not terminated.
 */
function gap(src: string, i: number): number {
  let j = ws(src, i);
  for (;;) {
    const pi = src.startsWith("<?", j);
    if (!pi && !src.startsWith("<!--", j)) {
      return j;
    }
    const end = src.indexOf(pi ? "?>" : "-->", j + (pi ? 2 : 4));
    if (end < 0) {
      return src.length + 1;
    }
    j = ws(src, end + (pi ? 2 : 3));
  }
}

/** The end of the name at `i` (xml.ts NAME), or -1. */
function nameEnd(src: string, i: number): number {
  if (!isNameStart(src.charCodeAt(i))) {
    return -1;
  }
  let j = i + 1;
  while (isNameChar(src.charCodeAt(j))) {
    j++;
  }
  return j;
}

/** The attribute at `i` (after its white space): name end, value start and end; null when not plain. */
interface Attr {
  nameEnd: number;
  from: number;
  to: number;
}

function attr(src: string, i: number): Attr | null {
  const ne = nameEnd(src, i);
  if (ne < 0) {
    return null;
  }
  let j = ws(src, ne);
  if (src.charCodeAt(j) !== 61) {
    return null;
  }
  j = ws(src, j + 1);
  const q = src.charCodeAt(j);
  const to = q === 34 || q === 39 ? src.indexOf(q === 34 ? '"' : "'", j + 1) : -1;
  if (to < 0) {
    return null;
  }
  for (let k = j + 1; k < to; k++) {
    const c = src.charCodeAt(k);
    if (c === 38 || c === 60) {
      return null; // a reference or '<': the general reader
    }
  }
  return { nameEnd: ne, from: j + 1, to };
}

/** Attributes from `i` to the tag's end: `each(name start, attr)` for each; the end ('>' or '/>' past), or -1. */
function attrs(src: string, i: number, each: (start: number, a: Attr) => boolean): { end: number; self: boolean } | null {
  let j = i;
  for (;;) {
    const k = ws(src, j);
    const c = src.charCodeAt(k);
    if (c === 62) {
      return { end: k + 1, self: false };
    }
    if (c === 47) {
      return src.charCodeAt(k + 1) === 62 ? { end: k + 2, self: true } : null;
    }
    const a = k > j ? attr(src, k) : null;
    if (a === null || !each(k, a)) {
      return null;
    }
    j = a.to + 1;
  }
}

/** The start tag at `i` (src[i] is '<'): its name, attributes in order, where it ends; null when not plain. */
function tag(src: string, i: number): Tag | null {
  const ne = nameEnd(src, i + 1);
  if (ne < 0) {
    return null;
  }
  const list: Array<[string, string]> = [];
  const end = attrs(src, ne, (k, a) => {
    const name = src.slice(k, a.nameEnd);
    if (list.some(([n]) => n === name)) {
      return false;
    }
    list.push([name, src.slice(a.from, a.to)]);
    return true;
  });
  return end === null ? null : { name: src.slice(i + 1, ne), attrs: list, ...end };
}

/** The end of the closing tag `</name>` at `i`, or -1. */
function closing(src: string, i: number, name: string): number {
  if (!src.startsWith("</", i)) {
    return -1;
  }
  const ne = nameEnd(src, i + 2);
  if (ne - i - 2 !== name.length || !src.startsWith(name, i + 2)) {
    return -1;
  }
  const j = ws(src, ne);
  return src.charCodeAt(j) === 62 ? j + 1 : -1;
}

/**
 * A self-closing <point> or <center> from `i` (after its name): its x and y appended to `points` (mapdoc.ts `num`:
 * other attributes are dropped); its end, or -1 (not plain, a repeated attribute, not a number).
 */
function readPoint(src: string, i: number, points: number[]): number {
  let x: string | undefined;
  let y: string | undefined;
  let others: string[] | null = null;
  const end = attrs(src, i, (k, a) => {
    const one = a.nameEnd === k + 1 ? src.charCodeAt(k) : 0;
    if (one === 120 || one === 121) {
      const v = src.slice(a.from, a.to);
      if ((one === 120 ? x : y) !== undefined) {
        return false;
      }
      x = one === 120 ? v : x;
      y = one === 121 ? v : y;
      return true;
    }
    const name = src.slice(k, a.nameEnd);
    if (others?.includes(name)) {
      return false;
    }
    (others ??= []).push(name);
    return true;
  });
  const px = x === undefined || x.trim() === "" ? Number.NaN : Number(x);
  const py = y === undefined || y.trim() === "" ? Number.NaN : Number(y);
  if (end === null || !end.self || !Number.isFinite(px) || !Number.isFinite(py)) {
    return -1;
  }
  points.push(px, py);
  return end.end;
}

/** mapdoc.ts `num`: the attribute's number, NaN where the general reader refuses it. */
function num(attrs: ReadonlyArray<[string, string]>, name: string): number {
  const raw = attrs.find(([k]) => k === name)?.[1];
  return raw === undefined || raw.trim() === "" ? Number.NaN : Number(raw);
}

/** The children of an object (all self-closing) from `i` to `</name>`, as mapdoc.ts `toObject` reads them. */
interface Parts {
  points: number[];
  r?: number;
  extra: XmlElement[];
}

/** One child at `j` (src[j] is '<', not a closing tag) into `parts`; its end, or -1. */
function readChild(src: string, j: number, parts: Parts): number {
  const ne = nameEnd(src, j + 1);
  const n = ne - j - 1;
  if ((n === 5 && src.startsWith("point", j + 1)) || (n === 6 && src.startsWith("center", j + 1))) {
    return readPoint(src, ne, parts.points);
  }
  const c = tag(src, j);
  if (c === null || !c.self) {
    return -1; // a child with content: the general reader
  }
  if (c.name === "radius" && parts.r === undefined) {
    parts.r = num(c.attrs, "r");
    return Number.isFinite(parts.r) ? c.end : -1;
  }
  parts.extra.push({ type: "element", name: c.name, attrs: c.attrs, children: [] });
  return c.end;
}

/** One object element at `i`; its end, or -1. */
function readObject(src: string, i: number, layer: number, objects: EditorObject[]): number {
  const t = tag(src, i);
  if (t === null) {
    return -1;
  }
  const parts: Parts = { points: [], extra: [] };
  let j = t.end;
  while (!t.self) {
    j = gap(src, j);
    if (src.charCodeAt(j) !== 60 || src.charCodeAt(j + 1) === 33) {
      return -1; // text, a CDATA section, a declaration, or the end
    }
    if (src.charCodeAt(j + 1) === 47) {
      j = closing(src, j, t.name);
      break;
    }
    j = readChild(src, j, parts);
    if (j < 0) {
      return -1;
    }
  }
  if (j < 0) {
    return -1;
  }
  // mapdoc.ts toObject, property for property
  const obj: EditorObject = { id: objects.length, kind: t.name, layer, points: parts.points, attrs: Object.fromEntries(t.attrs) };
  if (parts.r !== undefined) {
    obj.r = parts.r;
  }
  if (t.name === "hiddenlabel") {
    obj.text = obj.attrs.text ?? "";
  }
  if (parts.extra.length > 0) {
    obj.extra = parts.extra;
  }
  objects.push(obj);
  return j;
}

/** A layer's objects from `i` (after its start tag) to its closing tag; the end, or -1. */
function readLayer(src: string, i: number, layer: number, objects: EditorObject[]): number {
  let j = i;
  for (;;) {
    j = gap(src, j);
    if (src.charCodeAt(j) !== 60 || src.charCodeAt(j + 1) === 33) {
      return -1;
    }
    if (src.charCodeAt(j + 1) === 47) {
      return closing(src, j, "layer");
    }
    j = readObject(src, j, layer, objects);
    if (j < 0) {
      return -1;
    }
  }
}


/** The layers from `i` (after <map ...>) to </map>: the end, or -1. */
function readLayers(src: string, i: number, objects: EditorObject[], entries: RootEntry[]): number {
  let j = i;
  for (;;) {
    j = gap(src, j);
    if (src.startsWith("</", j)) {
      return closing(src, j, "map");
    }
    const t = src.charCodeAt(j) === 60 ? tag(src, j) : null;
    if (t === null || t.name !== "layer") {
      return -1; // text, a comment, an element beside the layers: the general reader
    }
    const index = Number(t.attrs.find(([k]) => k === "index")?.[1] ?? "0");
    if (!Number.isInteger(index)) {
      return -1;
    }
    entries.push({ layer: index, attrs: t.attrs });
    j = t.self ? t.end : readLayer(src, t.end, index, objects);
    if (j < 0) {
      return -1;
    }
  }
}

/** The document read the fast way, or null: read it with the general reader (mapdoc.ts `parseMapDoc`). */
export function readMapFast(src: string, name: string): MapDoc | null {
  if (src.length > MAX_XML_CHARS) {
    return null;
  }
  const at = gap(src, 0);
  const root = src.charCodeAt(at) === 60 && src.charCodeAt(at + 1) !== 33 ? tag(src, at) : null;
  if (root === null || root.name !== "map") {
    return null;
  }
  const objects: EditorObject[] = [];
  const entries: RootEntry[] = [];
  const end = root.self ? root.end : readLayers(src, root.end, objects, entries);
  if (end < 0 || gap(src, end) !== src.length) {
    return null;
  }
  const version = root.attrs.find(([k]) => k === "Version" || k === "version")?.[1] ?? null;
  return { scene: { name, version, objects }, rootAttrs: root.attrs, entries, nextId: objects.length };
}
