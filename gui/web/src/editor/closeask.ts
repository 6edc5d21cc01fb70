/**
 * guide 5.4 "Closes the toolbar and asks for saving if necessary" (and the roadmap editor, which "looks similar",
 * 5.5): without unsaved changes the editor closes at once; with them a dialog offers Save (then close), Close
 * without saving and Cancel. Resolves with what happened.
 */
import { h } from "../dom";
import { bind, type Key } from "../i18n/i18n";
import { dialog } from "../ui/dialog";
import type { Closing } from "./shell";

export type { Closing };

export async function askToClose(dirty: boolean, question: Key): Promise<Closing> {
  if (!dirty) {
    return "closed";
  }
  const ask = h("p");
  bind(ask, question, { name: false });
  const k = await dialog("edit.closeTitle", ask, ["edit.save", "edit.discard", "dialog.cancel"]);
  return k === 0 ? "saved" : k === 1 ? "discarded" : "cancelled";
}
