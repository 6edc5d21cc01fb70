/**
 * What the map view shows, as its subscriptions last set it: the platform's (or an open editor's) documents, the
 * last status, the ground truth and the editor's hold on the pointer. The view (panels/mapview.ts) alone writes
 * it; the camera controller, the layer cache and the renderer read it.
 */
import type { GetStatusReply } from "../../pltf";
import type { Bounds, MapScene } from "../../scene/map";
import type { Roadmap } from "../../scene/roadmap";
import type { EditHooks } from "../../session/edited";
import type { FleetBody } from "../../session/fleet";
import type { TruthEvent } from "../../session/session";

export interface Shown {
  readonly scene: MapScene | null;
  /** the scene's bounds (after an edit from the layer cache's boxes, without a pass over every object) */
  readonly bounds: Bounds | null;
  readonly roadmap: Roadmap | null;
  readonly status: GetStatusReply | null;
  /** the optional ground truth (control channel) */
  readonly truth: TruthEvent | null;
  /** set while an editor is open: the view shows its document and hands it the pointer in the tool "edit" */
  readonly hooks: EditHooks | null;
  /** a fleet's platforms (issue 30), the selected one among them; [] for a single platform */
  readonly fleet: FleetBody[];
}

/** The view's own copy, the one it writes. */
export type ShownState = { -readonly [K in keyof Shown]: Shown[K] };

export function nothingShown(): ShownState {
  return { scene: null, bounds: null, roadmap: null, status: null, truth: null, hooks: null, fleet: [] };
}
