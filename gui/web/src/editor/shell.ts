/**
 * The document shell both editors share (guide 5.4 and 5.5: the roadmap's toolbar "looks similar to the toolbar
 * of the map editor"): load from the platform, open a file, save, save as, new, undo and redo, send then verify,
 * and close with changes. What differs between a map and a roadmap is a small adapter (`DocumentKind`: parse,
 * serialise, check, compare, name, words); the platform is a `PlatformLink` (GET_x and SET_x of the document);
 * the dialogs and the download are `ShellEffects`. No DOM and no session here: shellbar.ts builds the buttons and
 * the real effects, the panels the adapters, and test/shell.test.ts drives it with an in-memory document.
 */
import type { Action, EditHistory, Said } from "./history";
import type { Verdict } from "./validate";

/** What a close with unsaved changes came to (closeask.ts asks). */
export type Closing = "closed" | "saved" | "discarded" | "cancelled";

/** What the shell reports; each kind words it from its own catalog entries (e.g. edit.loaded, rm.loaded). */
export type ShellEvent =
  | "loaded"
  | "opened"
  | "openFailed"
  | "saved"
  | "sent"
  | "active"
  | "notTaken"
  | "invalid"
  | "closed";

/** How a new document came: from the platform, from a file, or a blank one (New, or discarded at close). */
export type Replaced = "loaded" | "opened" | "new";

export type Words = Record<string, string | number>;

/** One kind of document: everything the shell needs to know about it. */
export interface DocumentKind<H extends EditHistory> {
  /** the file name's fallback and extension ("map", ".map") */
  readonly fallback: string;
  readonly ext: string;
  /** A fresh history over the document read from `text`; throws with the reason when it is not one. */
  parse(text: string, name: string): H;
  /** A fresh history over an empty document. */
  blank(): H;
  /** The document as the platform's XML; may throw with the reason. */
  serialise(history: H): string;
  /** The check before sending (the project's XSD, validate.ts). */
  validate(text: string): Promise<Verdict>;
  /** Whether the platform's document `got` holds what was sent (the verify of send-then-verify). */
  same(sent: string, got: string): boolean;
  /** The document's counts for the messages ({n} objects; {n} stations, {e} edges). */
  counts(history: H): Words;
  /** The message of an event in the user's language. */
  text(event: ShellEvent, words?: Words): string;
  /** The message of an action done, undone or redone ("Undone: add a line"), in the user's language. */
  action(said: Said, action: Action | null): string;
  /** The document took a new name (Save As); a kind that keeps its name inside the document stores it. */
  named?(history: H, name: string): void;
}

/** The platform's side of a document: its GET (answered) and its SET (no reply, guide 6.1). */
export interface PlatformLink {
  fetch(): Promise<{ text: string; name: string }>;
  send(name: string, text: string): void;
}

/** The panel around the shell. */
export interface ShellPanel<H extends EditHistory> {
  say(text: string): void;
  /** The document or its saved state changed: redraw, publish, update the buttons. */
  changed(): void;
  /** A new document is in the shell: the panel drops its selection and shows it (and calls `changed` itself). */
  replaced(how: Replaced): void;
  /** The document was not sent: `verdict` says why (the panel may point at the object of its line). */
  invalid?(verdict: Verdict & { ok: false }, text: string, history: H): void;
  /** The editor closes (the dock hides it). */
  close(): void;
}

/** What the shell asks of the page: a download, and the two dialogs. */
export interface ShellEffects {
  download(fileName: string, text: string): void;
  /** Close with unsaved changes? (resolves at once with "closed" when there are none) */
  askToClose(dirty: boolean): Promise<Closing>;
  /** Save As: the file name typed, or null when cancelled. */
  askFileName(suggested: string): Promise<string | null>;
}

/** A file name for a document named `name` (the platform's name, or "map"/"roadmap"), with its extension. */
export function fileNameOf(name: string, fallback: string, ext: string): string {
  const base = name.replace(/[\\/:*?"<>|]+/g, "_").trim() || fallback;
  return base.endsWith(ext) ? base : `${base}${ext}`;
}

const reason = (e: unknown): string => (e instanceof Error ? e.message : String(e));

export class DocumentShell<H extends EditHistory> {
  private current: H;
  private docName = "";

  constructor(
    private readonly kind: DocumentKind<H>,
    private readonly link: PlatformLink,
    private readonly panel: ShellPanel<H>,
    private readonly effects: ShellEffects,
  ) {
    this.current = kind.blank();
  }

  get history(): H {
    return this.current;
  }

  /** The document's name (the platform's, the file's without extension, or the one Save As gave it). */
  get name(): string {
    return this.docName;
  }

  /** The file name Save uses. */
  get fileName(): string {
    return fileNameOf(this.docName, this.kind.fallback, this.kind.ext);
  }

  private say(event: ShellEvent, words?: Words): void {
    this.panel.say(this.kind.text(event, words));
  }

  private replace(history: H, name: string, how: Replaced): void {
    this.current = history;
    this.docName = name;
    this.panel.replaced(how);
  }

  /** guide 5.4 "Load the map from the platform" (CMD_GET_MAP; 5.5 CMD_GET_ROADMAP). */
  async load(): Promise<void> {
    try {
      const got = await this.link.fetch();
      this.replace(this.kind.parse(got.text, got.name), got.name, "loaded");
      this.say("loaded", this.kind.counts(this.current));
    } catch (e) {
      this.panel.say(reason(e));
    }
  }

  /**
   * guide 5.4 "Load a map file from the hard disk of the PC": a malformed file or another kind of document is
   * refused with its reason and the editor keeps its content.
   */
  open(fileName: string, text: string): void {
    let history: H;
    const name = fileName.replace(/\.[^.]*$/, "");
    try {
      history = this.kind.parse(text, name);
    } catch (e) {
      this.say("openFailed", { file: fileName, why: reason(e) });
      return;
    }
    this.replace(history, name, "opened");
    this.say("opened", { file: fileName, ...this.kind.counts(history) });
  }

  /** guide 5.4 "Create a new map". */
  newDocument(): void {
    this.replace(this.kind.blank(), "", "new");
  }

  /** guide 5.4 "Save the current map to the local harddrive": the document as a download under `fileName`. */
  save(fileName = this.fileName): void {
    this.effects.download(fileName, this.kind.serialise(this.current));
    this.current.markSaved();
    this.say("saved", { file: fileName });
    this.panel.changed();
  }

  /** guide 5.4 "Save a map as a new file": the file name asked for; the document keeps it as its name. */
  async saveAs(): Promise<void> {
    const typed = await this.effects.askFileName(this.fileName);
    if (typed === null) {
      return;
    }
    const fileName = fileNameOf(typed, this.kind.fallback, this.kind.ext);
    this.docName = fileName.slice(0, fileName.length - this.kind.ext.length);
    this.kind.named?.(this.current, this.docName);
    this.save(fileName);
  }

  /** guide 5.4 "Undo": the action taken back is said ("Undone: add a line"), or that there was none. */
  undo(): void {
    const action = this.current.undo();
    this.panel.say(this.kind.action(action === null ? "nothingToUndo" : "undone", action));
    this.panel.changed();
  }

  /** guide 5.4 "Redo": the action done again is said ("Redone: add a line"), or that there was none. */
  redo(): void {
    const action = this.current.redo();
    this.panel.say(this.kind.action(action === null ? "nothingToRedo" : "redone", action));
    this.panel.changed();
  }

  /**
   * Send then verify (guide 5.4 "Send the current map to the platform"): checked against the project's XSD first
   * (an invalid document is not sent), sent by the SET telegram, which has no reply, then read back by the GET
   * telegram, answered after it (guide 6.1): the platform took it when the document read back holds what was
   * sent. The counts in the messages are those of the document sent.
   */
  /** Send the document; true once the platform got it (then read back), false when it was not sent. */
  async send(): Promise<boolean> {
    const history = this.current;
    const name = this.docName;
    let text: string;
    try {
      text = this.kind.serialise(history);
    } catch (e) {
      this.panel.say(reason(e));
      return false;
    }
    const verdict = await this.kind.validate(text);
    if (!verdict.ok) {
      this.panel.invalid?.(verdict, text, history);
      this.say("invalid", { why: verdict.message });
      this.panel.changed();
      return false;
    }
    const counts = this.kind.counts(history);
    try {
      this.link.send(name || "edited", text);
    } catch (e) {
      this.panel.say(reason(e));
      return false;
    }
    history.markSaved();
    this.say("sent", counts);
    this.panel.changed();
    try {
      const got = await this.link.fetch();
      this.say(this.kind.same(text, got.text) ? "active" : "notTaken", counts);
    } catch (e) {
      this.panel.say(reason(e));
    }
    return true;
  }

  /**
   * guide 5.4 "Closes the toolbar and asks for saving if necessary": Save saves and closes, Close without saving
   * drops the changes (a blank document) and closes, Cancel keeps the editor open.
   */
  async close(): Promise<Closing> {
    const how = await this.effects.askToClose(this.current.dirty);
    if (how === "saved") {
      this.save();
    } else if (how === "discarded") {
      this.newDocument();
    }
    if (how !== "cancelled") {
      this.panel.close();
      this.say("closed");
    }
    return how;
  }
}
