/**
 * The help overlay (issue 35): the GUI's keyboard shortcuts, each with what it does in the guide's words and where
 * it works. `?` (outside a text field) or the header's Help button opens it; Escape, its Close button or a click
 * beside it closes it, and the focus goes back where it was.
 *
 * Rules:
 * - The list is a table (`GUI_SHORTCUTS`) of the shortcuts the panels really handle: the menu's Ctrl+O (main.ts),
 *   the operation's Alt keys (panels/operation.ts), driving in Velocity and Joystick (Software) (panels/motion.ts),
 *   the map's h/j/k/l and wheel (panels/map/controller.ts); the map toolbar's keys (R, +, -) and the editors' come
 *   from the toolbars' own table (`SHORTCUTS` in ui/icons.ts), listed after these.
 * - While it is open it is modal: no key reaches the panels behind it (Alt+S does not start the platform, the arrow
 *   keys do not drive it).
 * - Texts come from the catalog (i18n/en_help.ts, de_help.ts) and follow the language at once.
 */
import { h } from "../dom";
import { bind, type Key, onLanguage, t } from "../i18n/i18n";
import "./help.css";
import { SHORTCUTS } from "./icons";

/** A shortcut: its keys (alternatives; `+` joins keys pressed together, a space separates keys that each work). */
export interface Shortcut {
  keys: readonly string[];
  what: Key;
  where: Key;
}

export const GUI_SHORTCUTS: readonly Shortcut[] = [
  { keys: ["?"], what: "help.do.help", where: "help.where.anywhere" },
  { keys: ["Escape"], what: "help.do.close", where: "help.where.open" },
  { keys: ["Ctrl+O"], what: "help.do.openSocket", where: "help.where.anywhere" },
  { keys: ["Alt+I"], what: "help.do.init", where: "help.where.anywhere" },
  { keys: ["Alt+S"], what: "help.do.start", where: "help.where.anywhere" },
  { keys: ["Alt+B"], what: "help.do.break", where: "help.where.anywhere" },
  { keys: ["Alt+C"], what: "help.do.continue", where: "help.where.anywhere" },
  { keys: ["Alt+X"], what: "help.do.stop", where: "help.where.anywhere" },
  { keys: ["Arrows", "W A S D"], what: "help.do.drive", where: "help.where.drive" },
  { keys: ["H J K L"], what: "help.do.pan", where: "help.where.map" },
  { keys: ["Wheel"], what: "help.do.zoom", where: "help.where.mapPointer" },
];

/** Every shortcut the overlay lists: the GUI's, then the editors'. */
export function allShortcuts(): Shortcut[] {
  return [...GUI_SHORTCUTS, ...SHORTCUTS.map((s) => ({ keys: [s.keys], what: s.what, where: s.where }))];
}

/** The catalog's name of a key that has one (Ctrl is Strg in German); other keys are shown as they are. */
const KEY_NAMES: Record<string, Key> = {
  Ctrl: "help.key.ctrl",
  Alt: "help.key.alt",
  Shift: "help.key.shift",
  Escape: "help.key.escape",
  Enter: "help.key.enter",
  Arrows: "help.key.arrows",
  Wheel: "help.key.wheel",
};

function keyName(k: string): string {
  const key = KEY_NAMES[k];
  return key === undefined ? k : t(key);
}

/** The keys of a shortcut as <kbd> elements: "Ctrl+O" -> Ctrl + O, "W A S D" -> W A S D, alternatives by "or". */
export function keysCell(keys: readonly string[]): HTMLElement {
  const cell = h("td", { class: "help-keys" });
  keys.forEach((alt, i) => {
    if (i > 0) {
      cell.append(` ${t("help.or")} `);
    }
    alt.split(" ").forEach((part, j) => {
      if (j > 0) {
        cell.append(" ");
      }
      part.split("+").forEach((k, n) => {
        if (n > 0) {
          cell.append("+");
        }
        cell.append(h("kbd", {}, keyName(k)));
      });
    });
  });
  return cell;
}

/** Is the key typed into a field (where `?` is a character, not a command)? */
function typing(e: KeyboardEvent): boolean {
  const el = e.target as HTMLElement | null;
  return el?.closest?.("input, select, textarea, [contenteditable='true']") != null;
}

export interface Help {
  /** the overlay (a modal dialog over the page, hidden while closed) */
  readonly root: HTMLElement;
  /** the Help button for the header */
  readonly button: HTMLButtonElement;
  open(): void;
  close(): void;
  readonly isOpen: boolean;
}

/** The help overlay and its button; the keys that open and close it are listened for on the window. */
export function helpOverlay(): Help {
  const body = h("tbody");
  const head = h("tr", {}, ...(["help.keys", "help.what", "help.where"] as Key[]).map((k) => bind(h("th"), k)));
  const title = bind(h("h2", { id: "help-title" }), "help.title", { name: false });
  const close = bind(h("button", { type: "button", class: "help-close" }), "help.close");
  const dialog = h(
    "div",
    { role: "dialog", "aria-modal": "true", "aria-labelledby": "help-title", class: "help", tabindex: "-1" },
    h("div", { class: "help-head" }, title, close),
    bind(h("p", { class: "help-hint" }), "help.hint", { name: false }),
    h("table", {}, h("thead", {}, head), body),
  );
  const root = h("div", { class: "help-backdrop", hidden: true }, dialog);
  const button = h(
    "button",
    { type: "button", class: "help-button", "aria-keyshortcuts": "?", "aria-haspopup": "dialog" },
    "?",
  );
  bind(button, "help.open", { text: false, title: "help.open" });
  onLanguage(() => {
    body.replaceChildren(
      ...allShortcuts().map((s) => h("tr", {}, keysCell(s.keys), h("td", {}, t(s.what)), h("td", {}, t(s.where)))),
    );
  });
  let back: HTMLElement | null = null;
  const help: Help = {
    root,
    button,
    open() {
      if (!root.hidden) {
        return;
      }
      back = document.activeElement instanceof HTMLElement ? document.activeElement : null;
      root.hidden = false;
      button.setAttribute("aria-expanded", "true");
      close.focus();
    },
    close() {
      if (root.hidden) {
        return;
      }
      root.hidden = true;
      button.setAttribute("aria-expanded", "false");
      back?.focus({ preventScroll: true });
      back = null;
    },
    get isOpen() {
      return !root.hidden;
    },
  };
  button.addEventListener("click", () => help.open());
  close.addEventListener("click", () => help.close());
  root.addEventListener("click", (e) => e.target === root && help.close());
  // capture, on the window: before the panels' own listeners on the document
  window.addEventListener(
    "keydown",
    (e) => {
      if (help.isOpen) {
        if (e.key === "Escape") {
          e.preventDefault();
          help.close();
        }
        if (e.key !== "Tab") {
          e.stopPropagation(); // modal: nothing behind it acts on a key
        }
      } else if (e.key === "?" && !e.ctrlKey && !e.altKey && !e.metaKey && !typing(e)) {
        e.preventDefault();
        help.open();
      }
    },
    true,
  );
  return help;
}

/** Put the Help button in `header` and the overlay on the page (main.ts). */
export function mountHelp(header: HTMLElement): Help {
  const help = helpOverlay();
  header.append(help.button);
  document.body.append(help.root);
  return help;
}
