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
import type { EditorObject, MapDoc, RootEntry } from "./mapmodel";
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

/**
 * The attribute read last by `attr` and the tag end read last by `tagEnd`: module state rather than an object per
 * attribute (a map of 50,000 lines has 200,000 of them; the garbage was a good part of the load's time).
 */
let attrName = 0;
let attrFrom = 0;
let attrTo = 0;
let tagSelf = false;

/** The attribute at `i` (after its white space) into attrName (its name's end), attrFrom, attrTo; false when not plain. */
function attr(src: string, i: number): boolean {
  const ne = nameEnd(src, i);
  if (ne < 0) {
    return false;
  }
  let j = ws(src, ne);
  if (src.charCodeAt(j) !== 61) {
    return false;
  }
  j = ws(src, j + 1);
  const q = src.charCodeAt(j);
  const to = q === 34 || q === 39 ? src.indexOf(q === 34 ? '"' : "'", j + 1) : -1;
  if (to < 0) {
    return false;
  }
  for (let k = j + 1; k < to; k++) {
    const c = src.charCodeAt(k);
    if (c === 38 || c === 60) {
      return false; // a reference or '<': the general reader
    }
  }
  attrName = ne;
  attrFrom = j + 1;
  attrTo = to;
  return true;
}

/** At `k` ('>' or '/'): the tag's end, tagSelf set; -1 when it is not one. */
function tagEnd(src: string, k: number): number {
  const c = src.charCodeAt(k);
  tagSelf = c === 47;
  if (c === 62) {
    return k + 1;
  }
  return c === 47 && src.charCodeAt(k + 1) === 62 ? k + 2 : -1;
}

const isTagEnd = (c: number): boolean => c === 62 || c === 47;

/** The start tag at `i` (src[i] is '<'): its name, attributes in order, where it ends; null when not plain. */
function tag(src: string, i: number): Tag | null {
  const ne = nameEnd(src, i + 1);
  if (ne < 0) {
    return null;
  }
  const list: Array<[string, string]> = [];
  let j = ne;
  for (;;) {
    const k = ws(src, j);
    if (isTagEnd(src.charCodeAt(k))) {
      const end = tagEnd(src, k);
      return end < 0 ? null : { name: src.slice(i + 1, ne), attrs: list, end, self: tagSelf };
    }
    if (k === j || !attr(src, k)) {
      return null;
    }
    const name = src.slice(k, attrName);
    if (list.some(([n]) => n === name)) {
      return null;
    }
    list.push([name, src.slice(attrFrom, attrTo)]);
    j = attrTo + 1;
  }
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

/** mapdoc.ts `num` of the text from..to: Number() of it, NaN when blank; plain integers read without a string. */
function numberAt(src: string, from: number, to: number): number {
  let k = from;
  const neg = src.charCodeAt(k) === 45;
  k += neg ? 1 : 0;
  if (k < to && to - k <= 15) {
    let v = 0;
    for (; k < to; k++) {
      const d = src.charCodeAt(k) - 48;
      if (d < 0 || d > 9) {
        break;
      }
      v = v * 10 + d;
    }
    if (k === to) {
      return neg ? -v : v; // at most 15 digits: exact, as Number() gives it
    }
  }
  const raw = src.slice(from, to);
  return raw.trim() === "" ? Number.NaN : Number(raw);
}

/**
 * A self-closing <point> or <center> from `i` (after its name): its x and y appended to `points` (mapdoc.ts `num`:
 * other attributes are dropped); its end, or -1 (not plain, a repeated attribute, not a number).
 */
function readPoint(src: string, i: number, points: number[]): number {
  let x = Number.NaN;
  let y = Number.NaN;
  let seen = 0; // 1: x, 2: y
  let others: string[] | null = null;
  let j = i;
  for (;;) {
    const k = ws(src, j);
    if (isTagEnd(src.charCodeAt(k))) {
      const end = tagEnd(src, k);
      if (end < 0 || !tagSelf || !Number.isFinite(x) || !Number.isFinite(y)) {
        return -1;
      }
      points.push(x, y);
      return end;
    }
    if (k === j || !attr(src, k)) {
      return -1;
    }
    const one = attrName === k + 1 ? src.charCodeAt(k) : 0;
    const bit = one === 120 ? 1 : one === 121 ? 2 : 0;
    if (bit !== 0) {
      if ((seen & bit) !== 0) {
        return -1;
      }
      seen |= bit;
      const v = numberAt(src, attrFrom, attrTo);
      x = bit === 1 ? v : x;
      y = bit === 2 ? v : y;
    } else {
      const name = src.slice(k, attrName);
      if (others?.includes(name)) {
        return -1;
      }
      (others ??= []).push(name);
    }
    j = attrTo + 1;
  }
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
  const obj: EditorObject = {
    id: objects.length,
    kind: t.name,
    layer,
    points: parts.points,
    attrs: Object.fromEntries(t.attrs),
  };
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
