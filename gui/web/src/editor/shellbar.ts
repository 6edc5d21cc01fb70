/**
 * The document shell's buttons and the page's side of it (shell.ts): the download, the Save As and the
 * close-with-changes dialogs, the file input, and the shell's buttons on an editor's toolbar, in the places the
 * guide's toolbars have them (5.4; 5.5 "looks similar"): Load, Open, Save, Save as, New first; Undo and Redo
 * after the editor's Clear; Send and Close where the editor puts them.
 */
import { field, h } from "../dom";
import { type Key, t } from "../i18n/i18n";
import { dialog } from "../ui/dialog";
import { askToClose } from "./closeask";
import { download, fileInput } from "./files";
import type { EditHistory } from "./history";
import type { DocumentShell, ShellEffects, ShellEvent, Words } from "./shell";
import type { Toolbar } from "./toolbar";

/** The catalog entries of one kind of document (editor.ts words a map, rm.* a roadmap). */
export interface ShellKeys {
  /** the file input's accept list */
  readonly accept: string;
  readonly open: Key;
  readonly new: Key;
  readonly saveAsTitle: Key;
  readonly closeAsk: Key;
  readonly events: Record<ShellEvent, Key>;
}

/** The shell's messages from the catalog. */
export function wording(keys: ShellKeys): (event: ShellEvent, words?: Words) => string {
  return (event, words) => t(keys.events[event], words);
}

/** The Save As dialog: the file name to save under, Enter or the first button saves; null when cancelled. */
function askFileName(title: Key, suggested: string): Promise<string | null> {
  const nameIn = h("input", { type: "text", value: suggested });
  nameIn.addEventListener(
    "keydown",
    (e) => e.key === "Enter" && (nameIn.closest(".dialog")?.querySelector("button") as HTMLElement | null)?.click(),
  );
  return dialog(title, field("edit.fileName", nameIn), ["edit.saveAs", "dialog.cancel"]).then((k) =>
    k === 0 ? nameIn.value : null,
  );
}

/** The page's effects: a download, the dialogs of `keys`. */
export function pageEffects(keys: ShellKeys): ShellEffects {
  return {
    download,
    askToClose: (dirty) => askToClose(dirty, keys.closeAsk),
    askFileName: (suggested) => askFileName(keys.saveAsTitle, suggested),
  };
}

export interface FileButtons {
  load: HTMLButtonElement;
  open: HTMLInputElement;
  /** the file input's icon button (its label) */
  openButton: HTMLLabelElement;
  save: HTMLButtonElement;
  saveAs: HTMLButtonElement;
  new: HTMLButtonElement;
}

/** Load from platform, Open (a file input), Save, Save as, New. */
export function fileButtons<H extends EditHistory, T extends string>(
  shell: DocumentShell<H>,
  bar: Toolbar<T>,
  keys: ShellKeys,
  say: (text: string) => void,
): FileButtons {
  const load = bar.action("edit.load", () => void shell.load());
  const open = fileInput(keys.accept, keys.open, say, (fileName, text) => shell.open(fileName, text));
  const openButton = bar.fileAction(keys.open, open);
  const save = bar.action("edit.save", () => shell.save());
  const saveAs = bar.action("edit.saveAs", () => void shell.saveAs());
  const fresh = bar.action(keys.new, () => shell.newDocument());
  return { load, open, openButton, save, saveAs, new: fresh };
}

/** Undo and Redo, enabled while there is something to undo (redo); `update` after each change. */
export function historyButtons<H extends EditHistory, T extends string>(
  shell: DocumentShell<H>,
  bar: Toolbar<T>,
): { undo: HTMLButtonElement; redo: HTMLButtonElement; update(): void } {
  const undo = bar.action("edit.undo", () => shell.undo());
  const redo = bar.action("edit.redo", () => shell.redo());
  return {
    undo,
    redo,
    update() {
      undo.disabled = !shell.history.canUndo;
      redo.disabled = !shell.history.canRedo;
    },
  };
}

/** Send to the platform (then read back). */
export function sendButton<H extends EditHistory, T extends string>(
  shell: DocumentShell<H>,
  bar: Toolbar<T>,
  fleet: { confirmSend(): Promise<boolean>; sent(): void } | null = null,
): HTMLButtonElement {
  // a fleet asks first when the document is another platform's, and it is that platform's once sent
  // (panels/fleet.ts, erratum E-GUI-012)
  return bar.action("edit.send", async () => {
    if ((await fleet?.confirmSend()) === false) {
      return;
    }
    if (await shell.send()) {
      fleet?.sent();
    }
  });
}

/** Close the toolbar (asks for saving if necessary). */
export function closeButton<H extends EditHistory, T extends string>(
  shell: DocumentShell<H>,
  bar: Toolbar<T>,
): HTMLButtonElement {
  return bar.action("edit.close", () => void shell.close());
}
