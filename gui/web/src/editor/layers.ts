/**
 * The layer new objects go into (guide 6.5 "Map": "A map consists of several layers", `<layer index=...>`). The
 * map editor offers the document's layers and the next free index, to start a new layer; it starts on the first
 * layer of the document it loaded (0 for a new map).
 *
 * Fidelity (issue 20, "an edit changes only the objects it touches"): a layer the document had stays as it was,
 * attributes included, even when its last object is deleted; a layer the editor starts is written only while it
 * holds objects (mapdoc.ts `mapDocToXml`), so undoing the first object added to it removes its <layer> again.
 */
import type { MapDoc } from "./mapdoc";

export interface LayerChoice {
  index: number;
  /** not in the document yet: an object added to it starts the layer */
  fresh: boolean;
}

/** The document's layer indices, ascending: its <layer> elements' and its objects' (a layer the editor started). */
export function documentLayers(doc: MapDoc): number[] {
  const seen = new Set<number>();
  for (const e of doc.entries) {
    if ("layer" in e) {
      seen.add(e.layer);
    }
  }
  for (const o of doc.scene.objects) {
    seen.add(o.layer);
  }
  return [...seen].sort((a, b) => a - b);
}

/** The layer the editor starts on: the document's first <layer> in document order, else its first object's, else 0. */
export function defaultLayer(doc: MapDoc): number {
  for (const e of doc.entries) {
    if ("layer" in e) {
      return e.layer;
    }
  }
  return doc.scene.objects[0]?.layer ?? 0;
}

/**
 * What the "Layer for new objects" control offers: the document's layers, the next free index (one above the
 * highest, 0 for a map without layers) and the chosen layer when it is neither (a layer started, then undone).
 */
export function layerChoices(doc: MapDoc, chosen: number): LayerChoice[] {
  const have = documentLayers(doc);
  const next = have.length === 0 ? 0 : Math.max(0, have[have.length - 1] + 1);
  const fresh = new Set([next, chosen].filter((k) => !have.includes(k)));
  return [
    ...have.map((index) => ({ index, fresh: false })),
    ...[...fresh].map((index) => ({ index, fresh: true })),
  ].sort((a, b) => a.index - b.index);
}
