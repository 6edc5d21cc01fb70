/**
 * One history interface for both editors (guide 5.4 "Undo", "Redo"; 5.5 the roadmap's toolbar "looks similar"):
 * the document shell (shell.ts) and the Undo/Redo buttons see only this. Two implementations keep their own way
 * of storing a step: the map's `History` (commands.ts) keeps each command's changed objects, so a step on a map of
 * 50,000 objects touches only its objects; the roadmap's `RoadmapHistory` (roadmapdoc.ts) keeps whole copies of a
 * document of a few hundred stations, so an edit is any function of the document.
 *
 * A step is named by an `Action`: a catalog key (`act.*`, "add a line") and its words, worded in the user's
 * language when it is said, so "Undone: add a line" follows a language switch made after the edit (issue 35).
 */
import type { Key } from "../i18n/i18n";

export type Words = Record<string, string | number>;

/** What a step of the history did: the catalog key that names it and the words the key's text takes. */
export interface Action {
  readonly key: Key;
  readonly words?: Words;
}

export interface EditHistory {
  /** Take back the last action; the action, or null when there was nothing to undo. */
  undo(): Action | null;
  /** Do again the last action undone; the action, or null when there was nothing to redo. */
  redo(): Action | null;
  readonly canUndo: boolean;
  readonly canRedo: boolean;
  /** The last action done (the one Undo takes back); null when there is nothing to undo. */
  readonly label: Action | null;
  /** Mark the document saved (or sent): `dirty` is false until the next change, undo or redo. */
  markSaved(): void;
  readonly dirty: boolean;
}

/** The catalog's wording: `t` in the page, a stand-in in the unit tests. */
export type Wording = (key: Key, words?: Words) => string;

/** How an action is reported: done (a tool), undone (Undo), redone (Redo), or nothing to undo (redo). */
export type Said = "done" | "undone" | "redone" | "nothingToUndo" | "nothingToRedo";

const SAID: Record<Said, Key> = {
  done: "edit.actionDone",
  undone: "edit.undone",
  redone: "edit.redone",
  nothingToUndo: "edit.nothingToUndo",
  nothingToRedo: "edit.nothingToRedo",
};

/** The message of `action` said as `said` ("Undone: add a line"), in the catalog's words. */
export function actionMessage(said: Said, action: Action | null, text: Wording): string {
  return text(SAID[said], { action: action === null ? "" : text(action.key, action.words) });
}

/** The action of a step (`key`, `words`). */
export const act = (key: Key, words?: Words): Action => (words === undefined ? { key } : { key, words });
