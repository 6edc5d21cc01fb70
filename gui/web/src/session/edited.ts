/**
 * The document an open editor shows on the map view (issue 31): the editors publish it on the session's `edited`
 * topic, the map view subscribes, as every other panel subscribes to the platform's topics. Plain data and the
 * editor's hold on the pointer; nothing here draws or sends.
 */
import type { MapScene } from "../scene/map";
import type { Roadmap } from "../scene/roadmap";
import type { Camera } from "../view/camera";

/** An editor's hold on the view in its "edit" tool: pointer events in world mm, and its own drawing on top. */
export interface EditHooks {
  /** `button`: 0 left, 2 right (a right-click finishes a polygon) */
  down(x: number, y: number, pxPerMm: number, button: number): void;
  move(x: number, y: number): void;
  up(x: number, y: number): void;
  draw(ctx: CanvasRenderingContext2D, cam: Camera): void;
}

/**
 * The edited document, published at every change while its editor is open; `null` when the editor closes (the
 * view shows the platform's documents again once they are read). `shows` names the platform's document the
 * editor's stands in for: a GET_MAP (GET_ROADMAP) answered while the editor is open leaves the editor's document
 * on the view; the other document is still the platform's, so the roadmap editor places its stations over the
 * platform's map even when that map came late.
 */
export type EditedDocument =
  | { readonly shows: "map"; readonly scene: MapScene; readonly hooks: EditHooks }
  | { readonly shows: "roadmap"; readonly roadmap: Roadmap; readonly hooks: EditHooks };
