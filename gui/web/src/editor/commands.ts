/**
 * The editor's commands and its history (guide 5.4 "Undo", "Redo"; unbounded while the editor is open).
 *
 * A command is data: the objects it replaces, inserts or removes, each with its position in the document, so
 * doing it and undoing it are the same small function and an edit touches only its objects. The builders below
 * read the document and return a command (or, for a geometric operation with no solution, the reason, the
 * document untouched); `History.run` applies it.
 */
import type { Key } from "../i18n/i18n";
import { KINDS, type Kind, type MapObject } from "../scene/map";
import * as g from "./geometry";
import { type Action, act, type EditHistory } from "./history";
import type { MapDoc } from "./mapdoc";
import { inDocumentOrder, ObjectIndex } from "./objindex";

export interface Change {
  index: number;
  before: MapObject | null;
  after: MapObject | null;
}

export interface Command {
  label: Action;
  changes: Change[];
}

function applyChanges(doc: MapDoc, changes: readonly Change[]): void {
  const objs = doc.scene.objects;
  for (const c of changes) {
    if (c.before === null && c.after !== null) {
      objs.splice(c.index, 0, c.after);
      doc.nextId = Math.max(doc.nextId, c.after.id + 1);
    } else if (c.before !== null && objs[c.index]?.id !== c.before.id) {
      throw new Error(`command out of step with the document at object ${c.before.id}`);
    } else if (c.after === null) {
      objs.splice(c.index, 1);
    } else {
      objs[c.index] = c.after;
    }
  }
}

const inverse = (changes: readonly Change[]): Change[] =>
  changes.map((c) => ({ index: c.index, before: c.after, after: c.before })).reverse();

export class History implements EditHistory {
  private done: Command[] = [];
  private undone: Command[] = [];
  private saved: Command | null = null;
  /** the spatial index of the document's objects (objindex.ts), built at the first query, kept in step after */
  private idx: ObjectIndex | null = null;
  /** the document's objects by id, built at the first look-up, kept in step after */
  private ids: Map<number, MapObject> | null = null;

  constructor(public readonly doc: MapDoc) {}

  private apply(changes: readonly Change[]): void {
    try {
      applyChanges(this.doc, changes);
    } catch (e) {
      this.idx = null; // the document may be changed in part
      this.ids = null;
      throw e;
    }
    const ids = this.ids ?? new Map<number, MapObject>();
    for (const c of this.ids === null ? [] : changes) {
      if (c.before !== null && ids.get(c.before.id) === c.before) {
        ids.delete(c.before.id);
      }
      if (c.after !== null) {
        ids.set(c.after.id, c.after);
      }
    }
    const idx = this.idx;
    for (const c of idx === null ? [] : changes) {
      if (c.before !== null) {
        idx!.remove(c.before);
      }
      if (c.after !== null) {
        idx!.add(c.after);
      }
    }
    if (idx !== null && !idx.ok) {
      this.idx = null; // out of step: built again at the next query
    }
  }

  /** The object with id `id` (the document's ids are unique), without a pass over the document; undefined: none. */
  byId(id: number | null): MapObject | undefined {
    if (id === null) {
      return undefined;
    }
    this.ids ??= new Map(this.doc.scene.objects.map((o) => [o.id, o]));
    return this.ids.get(id);
  }

  /** Build the spatial index now (off an edit's path, e.g. a while after a map is loaded). */
  index(): ObjectIndex {
    this.idx ??= new ObjectIndex(this.doc.scene.objects);
    return this.idx;
  }

  /**
   * The objects that may lie within `tol` mm of (x, y), in document order: every object whose point or outline is
   * that near is among them (the hit tests then run on these alone). All objects when the index cannot say.
   */
  near(x: number, y: number, tol: number): readonly MapObject[] {
    const objects = this.doc.scene.objects;
    const cands = this.index().near(x, y, tol);
    if (cands === null) {
      return objects;
    }
    const { list, stale } = inDocumentOrder(objects, cands);
    if (stale) {
      this.idx = null;
      return objects;
    }
    return list;
  }

  run(cmd: Command): void {
    this.apply(cmd.changes);
    this.done.push(cmd);
    this.undone = [];
  }

  /** The action of the command undone, or null when there is nothing to undo. */
  undo(): Action | null {
    const cmd = this.done.pop();
    if (cmd === undefined) {
      return null;
    }
    this.apply(inverse(cmd.changes));
    this.undone.push(cmd);
    return cmd.label;
  }

  redo(): Action | null {
    const cmd = this.undone.pop();
    if (cmd === undefined) {
      return null;
    }
    this.apply(cmd.changes);
    this.done.push(cmd);
    return cmd.label;
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

  /** Mark the document saved (or sent): `dirty` is false until the next change, undo or redo. */
  markSaved(): void {
    this.saved = this.done[this.done.length - 1] ?? null;
  }

  get dirty(): boolean {
    return (this.done[this.done.length - 1] ?? null) !== this.saved;
  }
}

function indexOf(doc: MapDoc, id: number): number {
  const k = doc.scene.objects.findIndex((o) => o.id === id);
  if (k < 0) {
    throw new Error(`no object ${id} in the map`);
  }
  return k;
}

/** The action of adding an object of `kind` (issue 35: the history's labels are catalog keys). */
const ADD_KEY: Record<Kind, Key> = {
  line: "act.addLine",
  auxline: "act.addAuxline",
  linemapped: "act.addLine",
  auxlinemapped: "act.addAuxline",
  reflmark: "act.addReflector",
  circle: "act.addCircle",
  workarea: "act.addWorkarea",
  prohibit: "act.addProhibit",
  hiddenpolygon: "act.addHiddenpolygon",
  hiddenlabel: "act.addLabel",
};

export function addAction(kind: string): Action {
  const key = ADD_KEY[kind as Kind];
  return key === undefined ? act("act.addObject", { kind }) : act(key);
}

/** Add an object (its id is the document's next) at the end of the document. */
export function addObject(doc: MapDoc, obj: Omit<MapObject, "id">, label = addAction(obj.kind)): Command {
  const after: MapObject = { ...obj, id: doc.nextId, points: [...obj.points], attrs: { ...obj.attrs } };
  return { label, changes: [{ index: doc.scene.objects.length, before: null, after }] };
}

/** Delete objects (highest position first, so the positions stay right). */
export function deleteObjects(doc: MapDoc, ids: Iterable<number>, label = act("act.delete")): Command {
  const at = [...new Set(ids)].map((id) => indexOf(doc, id)).sort((a, b) => b - a);
  return { label, changes: at.map((index) => ({ index, before: doc.scene.objects[index], after: null })) };
}

/**
 * Clear the map (guide 5.4 "Clear the map"), undoable like any edit. Elements of a kind the editor does not know
 * are kept (it neither draws nor edits them).
 */
export function clearMap(doc: MapDoc): Command {
  const known = new Set<string>(KINDS);
  return deleteObjects(
    doc,
    doc.scene.objects.filter((o) => known.has(o.kind)).map((o) => o.id),
    act("act.clear"),
  );
}

function replace(doc: MapDoc, id: number, points: number[], label: Action): Command {
  const index = indexOf(doc, id);
  const before = doc.scene.objects[index];
  return { label, changes: [{ index, before, after: { ...before, points } }] };
}

/** Move objects by (dx, dy) mm (guide 5.4 "Edit objects in the map by drag and drop"). */
export function moveObjects(doc: MapDoc, ids: Iterable<number>, dx: number, dy: number): Command {
  const changes: Change[] = [];
  for (const id of new Set(ids)) {
    const index = indexOf(doc, id);
    const before = doc.scene.objects[index];
    const points = before.points.map((v, k) => g.clean(v + (k % 2 === 0 ? dx : dy)));
    changes.push({ index, before, after: { ...before, points } });
  }
  return { label: act("act.move"), changes };
}

/** Move one vertex of a polygon or line (guide 5.4 "Edit vertices of a polygon"). */
export function moveVertex(doc: MapDoc, id: number, vertex: number, p: g.Pt): Command {
  const before = doc.scene.objects[indexOf(doc, id)];
  if (vertex < 0 || 2 * vertex + 1 >= before.points.length) {
    throw new Error(`object ${id} has no vertex ${vertex}`);
  }
  const points = [...before.points];
  points[2 * vertex] = p.x;
  points[2 * vertex + 1] = p.y;
  return replace(doc, id, points, act("act.moveVertex"));
}

export function segOf(o: MapObject): g.Result<g.Seg> {
  if (o.points.length !== 4) {
    return { ok: false, reason: `a <${o.kind}> is not a line` };
  }
  const [x0, y0, x1, y1] = o.points;
  return { ok: true, value: { a: { x: x0, y: y0 }, b: { x: x1, y: y1 } } };
}

type LineOp = (s: g.Seg, r: g.Seg) => g.Result<g.Seg>;

/** A geometric operation of line `id` against reference line `refId`: a command, or why not (nothing changed). */
export function lineOp(doc: MapDoc, label: Action, op: LineOp, id: number, refId: number): g.Result<Command> {
  if (id === refId) {
    return { ok: false, reason: "the reference line is the line itself" };
  }
  const s = segOf(doc.scene.objects[indexOf(doc, id)]);
  const r = segOf(doc.scene.objects[indexOf(doc, refId)]);
  if (!s.ok || !r.ok) {
    return { ok: false, reason: !s.ok ? s.reason : (r as { reason: string }).reason };
  }
  const out = op(s.value, r.value);
  if (!out.ok) {
    return out;
  }
  const { a, b } = out.value;
  return { ok: true, value: replace(doc, id, [a.x, a.y, b.x, b.y], label) };
}

/** Invert a line's direction (guide 5.4): its front turns to the other side. */
export function invertLine(doc: MapDoc, id: number): g.Result<Command> {
  const s = segOf(doc.scene.objects[indexOf(doc, id)]);
  if (!s.ok) {
    return s;
  }
  const out = g.invert(s.value);
  if (!out.ok) {
    return out;
  }
  const { a, b } = out.value;
  return { ok: true, value: replace(doc, id, [a.x, a.y, b.x, b.y], act("act.invert")) };
}

/** Add several objects as one step of the history (e.g. every line converted from one scan). */
export function addObjects(doc: MapDoc, objs: ReadonlyArray<Omit<MapObject, "id">>, label: Action): Command {
  const n = doc.scene.objects.length;
  const changes = objs.map((o, k) => ({
    index: n + k,
    before: null,
    after: { ...o, id: doc.nextId + k, points: [...o.points], attrs: { ...o.attrs } },
  }));
  return { label, changes };
}

/** Typed coordinates (typed.ts): the object's points, radius and text replaced; its other attributes kept. */
export function setGeometry(doc: MapDoc, id: number, g: { points: number[]; r?: number; text?: string }): Command {
  const index = indexOf(doc, id);
  const before = doc.scene.objects[index];
  const after: MapObject = { ...before, points: [...g.points] };
  if (g.r !== undefined) {
    after.r = g.r;
  }
  if (g.text !== undefined) {
    after.text = g.text;
    after.attrs = { ...before.attrs, text: g.text };
  }
  return { label: act("act.typed"), changes: [{ index, before, after }] };
}

/** Add `obj` and remove the objects `ids` in one step (a new workarea replaces the old one). */
export function addReplacing(doc: MapDoc, obj: Omit<MapObject, "id">, ids: readonly number[], label: Action): Command {
  const removed = deleteObjects(doc, ids).changes;
  const after: MapObject = { ...obj, id: doc.nextId, points: [...obj.points], attrs: { ...obj.attrs } };
  return { label, changes: [...removed, { index: doc.scene.objects.length - removed.length, before: null, after }] };
}

/** The kinds whose vertices can be added and removed (a polygon keeps at least 3, map.xsd allows it). */
const POLYGONS = new Set(["workarea", "prohibit", "hiddenpolygon"]);
const MIN_VERTICES = 3;

/** Insert a vertex after vertex `after` of a polygon (guide 5.4 "Edit vertices of a polygon"). */
export function insertVertex(doc: MapDoc, id: number, after: number, p: g.Pt): g.Result<Command> {
  const before = doc.scene.objects[indexOf(doc, id)];
  if (!POLYGONS.has(before.kind)) {
    return { ok: false, reason: `a <${before.kind}> has a fixed number of points: only a polygon gets new vertices` };
  }
  const points = [...before.points];
  points.splice(2 * (after + 1), 0, g.clean(p.x), g.clean(p.y));
  return { ok: true, value: replace(doc, id, points, act("act.addVertex")) };
}

/** Delete vertex `vertex` of a polygon; a polygon keeps at least 3. */
export function deleteVertex(doc: MapDoc, id: number, vertex: number): g.Result<Command> {
  const before = doc.scene.objects[indexOf(doc, id)];
  if (!POLYGONS.has(before.kind)) {
    return { ok: false, reason: `a <${before.kind}> has a fixed number of points: only a polygon loses vertices` };
  }
  if (before.points.length / 2 <= MIN_VERTICES) {
    return { ok: false, reason: `a polygon keeps at least ${MIN_VERTICES} vertices: delete the polygon instead` };
  }
  const points = [...before.points];
  points.splice(2 * vertex, 2);
  return { ok: true, value: replace(doc, id, points, act("act.deleteVertex")) };
}
