/**
 * The roadmap editor's document (guide 5.5; format guide 6.5 "Roadmap"): stations (id, name, pose) and edges
 * between stations with their path points, plus what the editor does not model (the root's attributes, unknown
 * attributes of stations and edges, elements outside <stations> and <edges>), kept and written back.
 *
 * The history keeps whole snapshots: a roadmap is small (tens of stations), so an edit, its undo and its redo
 * are exact copies, unbounded while the editor is open.
 */
import { type Action, act, type EditHistory } from "./history";
import { elementsOf, parseXml, writeDocument, type XmlElement } from "./xml";

export interface RmStation {
  id: string;
  name: string;
  x: number;
  y: number;
  /** degrees (guide 6.5 station "angle"; absent means 0, E-XML-007) */
  angle: number;
  attrs: Array<[string, string]>;
}

export interface RmEdge {
  start: string;
  end: string;
  /** the path points between the stations: x0, y0, x1, y1, ... mm */
  points: number[];
  attrs: Array<[string, string]>;
}

export interface RoadmapDoc {
  rootAttrs: Array<[string, string]>;
  stations: RmStation[];
  edges: RmEdge[];
  /** children of <roadmap> other than <stations> and <edges>, kept as they were */
  kept: XmlElement[];
}

export class RoadmapDocError extends Error {}

const attr = (el: XmlElement, name: string): string | undefined => el.attrs.find(([k]) => k === name)?.[1];
const others = (el: XmlElement, known: string[]): Array<[string, string]> =>
  el.attrs.filter(([k]) => !known.includes(k));

function coord(el: XmlElement, name: string, owner: string): number {
  const raw = attr(el, name);
  const v = raw === undefined || raw.trim() === "" ? Number.NaN : Number(raw);
  if (!Number.isFinite(v)) {
    throw new RoadmapDocError(`${owner} has a <point> without a number in ${name}`);
  }
  return v;
}

function pointsOf(el: XmlElement, owner: string): number[] {
  const out: number[] = [];
  for (const c of elementsOf(el)) {
    if (c.name === "point") {
      out.push(coord(c, "x", owner), coord(c, "y", owner));
    } else if (c.name === "points") {
      out.push(...pointsOf(c, owner));
    }
  }
  return out;
}

function station(el: XmlElement): RmStation {
  const id = attr(el, "id") ?? "";
  const owner = `station ${JSON.stringify(id)}`;
  const p = elementsOf(el).find((c) => c.name === "point");
  if (p === undefined) {
    throw new RoadmapDocError(`${owner} has no <point>`);
  }
  const angle = Number(attr(el, "angle") ?? "0");
  if (!Number.isFinite(angle)) {
    throw new RoadmapDocError(`${owner} has an angle that is not a number`);
  }
  const name = attr(el, "name") ?? id;
  return {
    id,
    name,
    x: coord(p, "x", owner),
    y: coord(p, "y", owner),
    angle,
    attrs: others(el, ["id", "name", "angle"]),
  };
}

function edge(el: XmlElement): RmEdge {
  const start = attr(el, "startstation") ?? "";
  const end = attr(el, "endstation") ?? "";
  const points = pointsOf(el, `edge ${start} -> ${end}`);
  return { start, end, points, attrs: others(el, ["startstation", "endstation"]) };
}

/** Read a roadmap document; RoadmapDocError (one line) when it is not well-formed or not a roadmap. */
export function parseRoadmapDoc(src: string): RoadmapDoc {
  if (src.trim() === "") {
    return newRoadmapDoc();
  }
  let root: XmlElement;
  try {
    root = parseXml(src);
  } catch (e) {
    throw new RoadmapDocError(`the roadmap is not well-formed XML: ${(e as Error).message}`);
  }
  if (root.name !== "roadmap") {
    throw new RoadmapDocError(`expected a <roadmap> document, got <${root.name}>`);
  }
  const doc: RoadmapDoc = { rootAttrs: root.attrs, stations: [], edges: [], kept: [] };
  for (const el of elementsOf(root)) {
    if (el.name === "stations") {
      doc.stations.push(
        ...elementsOf(el)
          .filter((c) => c.name === "station")
          .map(station),
      );
    } else if (el.name === "edges") {
      doc.edges.push(
        ...elementsOf(el)
          .filter((c) => c.name === "edge")
          .map(edge),
      );
    } else {
      doc.kept.push(el);
    }
  }
  return doc;
}

const el = (name: string, attrs: Array<[string, string]>, children: XmlElement[] = []): XmlElement => ({
  type: "element",
  name,
  attrs,
  children,
});
const point = (x: number, y: number): XmlElement =>
  el("point", [
    ["x", String(x)],
    ["y", String(y)],
  ]);

/** The document as XML (the <points> wrapper of E-XML-003 for every edge's path points). */
export function writeRoadmapDoc(doc: RoadmapDoc): string {
  const stations = doc.stations.map((s) =>
    el("station", [["id", s.id], ["name", s.name], ["angle", String(s.angle)], ...s.attrs], [point(s.x, s.y)]),
  );
  const edges = doc.edges.map((e) => {
    const pts: XmlElement[] = [];
    for (let i = 0; i + 1 < e.points.length; i += 2) {
      pts.push(point(e.points[i], e.points[i + 1]));
    }
    return el("edge", [["startstation", e.start], ["endstation", e.end], ...e.attrs], [el("points", [], pts)]);
  });
  const children = [el("stations", [], stations), el("edges", [], edges), ...doc.kept];
  return writeDocument(el("roadmap", doc.rootAttrs, children));
}

/** Whether two roadmap documents are the same once read and written (false when either does not parse). */
export function sameRoadmap(a: string, b: string): boolean {
  const norm = (src: string): string | null => {
    try {
      return writeRoadmapDoc(parseRoadmapDoc(src));
    } catch {
      return null;
    }
  };
  const na = norm(a);
  return na !== null && na === norm(b);
}

export function newRoadmapDoc(): RoadmapDoc {
  return { rootAttrs: [["Version", "1.0"]], stations: [], edges: [], kept: [] };
}

const copy = (d: RoadmapDoc): RoadmapDoc => structuredClone(d);

/** A fresh station id (an XML ID, E-XML-014): s1, s2, ... not yet used. */
export function nextStationId(doc: RoadmapDoc): string {
  const used = new Set(doc.stations.map((s) => s.id));
  let n = doc.stations.length + 1;
  while (used.has(`s${n}`)) {
    n++;
  }
  return `s${n}`;
}

export type Edit = (doc: RoadmapDoc) => string | null;

/** One step of a RoadmapHistory: the documents before and after it and the label of the edit. */
interface Step {
  readonly before: RoadmapDoc;
  readonly after: RoadmapDoc;
  readonly label: Action;
}

/**
 * Edits of a roadmap with unbounded undo and redo (guide 5.5, like the map editor's 5.4). A step keeps the whole
 * documents on both sides of it (a roadmap is a few hundred stations), so an edit is any function of a copy; a
 * step moves between the undo and the redo stack as it is, as the map's commands do.
 */
export class RoadmapHistory implements EditHistory {
  private done: Step[] = [];
  private undone: Step[] = [];
  /** the step that led to the saved document (null: the document as loaded) */
  private saved: Step | null = null;

  constructor(public doc: RoadmapDoc) {}

  /** Apply `edit` to a copy; it returns null when done or the reason it cannot be done (nothing changes). */
  run(edit: Edit, label: Action = act("act.edit")): string | null {
    const next = copy(this.doc);
    const why = edit(next);
    if (why !== null) {
      return why;
    }
    this.done.push({ before: this.doc, after: next, label });
    this.undone = [];
    this.doc = next;
    return null;
  }

  undo(): Action | null {
    const step = this.done.pop();
    if (step === undefined) {
      return null;
    }
    this.undone.push(step);
    this.doc = step.before;
    return step.label;
  }

  redo(): Action | null {
    const step = this.undone.pop();
    if (step === undefined) {
      return null;
    }
    this.done.push(step);
    this.doc = step.after;
    return step.label;
  }

  get canUndo(): boolean {
    return this.done.length > 0;
  }

  get canRedo(): boolean {
    return this.undone.length > 0;
  }

  get label(): Action | null {
    return this.done[this.done.length - 1]?.label ?? null;
  }

  markSaved(): void {
    this.saved = this.done[this.done.length - 1] ?? null;
  }

  get dirty(): boolean {
    return (this.done[this.done.length - 1] ?? null) !== this.saved;
  }
}

/** Add a station at (x, y) mm facing `angle` degrees. */
export const addStation =
  (name: string, x: number, y: number, angle: number): Edit =>
  (doc) => {
    if (!/^[-A-Za-z0-9_.:]+$/.test(name)) {
      return `a station's name is one word of letters, digits, '_', '-', '.' (got ${JSON.stringify(name)})`;
    }
    if (doc.stations.some((s) => s.name === name)) {
      return `there is already a station named ${name}`;
    }
    doc.stations.push({ id: nextStationId(doc), name, x, y, angle, attrs: [] });
    return null;
  };

/** Add an edge between two stations (by id). */
export const addEdge =
  (start: string, end: string): Edit =>
  (doc) => {
    if (start === end) {
      return "an edge joins two different stations";
    }
    if (doc.edges.some((e) => (e.start === start && e.end === end) || (e.start === end && e.end === start))) {
      return "these stations are already joined";
    }
    doc.edges.push({ start, end, points: [], attrs: [] });
    return null;
  };

/** Delete a station and the edges at it. */
export const deleteStation =
  (id: string): Edit =>
  (doc) => {
    const k = doc.stations.findIndex((s) => s.id === id);
    if (k < 0) {
      return `no station ${id}`;
    }
    doc.stations.splice(k, 1);
    doc.edges = doc.edges.filter((e) => e.start !== id && e.end !== id);
    return null;
  };

/** Move a station to (x, y) mm. */
export const moveStation =
  (id: string, x: number, y: number): Edit =>
  (doc) => {
    const s = doc.stations.find((t) => t.id === id);
    if (s === undefined) {
      return `no station ${id}`;
    }
    s.x = x;
    s.y = y;
    return null;
  };

/** Clear the roadmap (guide 5.5 "Clear"), undoable. */
export const clearRoadmap: Edit = (doc) => {
  doc.stations = [];
  doc.edges = [];
  return null;
};
