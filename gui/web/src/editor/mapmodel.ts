/**
 * The map editor's document model (guide 5.4; format guide 6.5 "Map"): the scene the view draws plus what the
 * scene does not model. Both readers fill it: the general one (mapdoc.ts) and the fast one (mapfast.ts).
 */
import type { MapObject, MapScene } from "../scene/map";
import type { XmlElement } from "./xml";

/** One child of <map>, in document order: a layer (its objects are the scene's of that index) or kept as is. */
export type RootEntry = { layer: number; attrs: Array<[string, string]> } | { kept: XmlElement };

export interface MapDoc {
  scene: MapScene;
  rootAttrs: Array<[string, string]>;
  entries: RootEntry[];
  /** The id the next new object gets. */
  nextId: number;
}

export interface EditorObject extends MapObject {
  /** Child elements other than point, center and radius, kept in order. */
  extra?: XmlElement[];
}
