/**
 * The editors' toolbar, one builder for both (guide 5.5: the roadmap's toolbar "looks similar to the toolbar of
 * the map editor"): a caption naming the editor above a `role=toolbar` of icon buttons (ui/icons.ts). Each button's
 * accessible name is the catalog's word for it (the guide's), its tooltip (`title`) the guide's description of the
 * tool, shown also at the bottom of the toolbar while the button is pointed at or focused (guide 5.4 "Tooltips of
 * each tool are displayed at the bottom of the toolbar"). Actions run once per click; of the tools one at a time
 * is pressed (aria-pressed), the panel deciding what picking one does.
 */
import { h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import { icon } from "../ui/icons";

export class Toolbar<T extends string> {
  /** the caption and the toolbar */
  readonly root: HTMLElement;
  /** the toolbar itself (role=toolbar) */
  readonly bar: HTMLElement = h("div", { role: "toolbar", class: "edit-tools" });
  /** The tools' buttons, in the order they were added. */
  readonly tools = new Map<T, HTMLButtonElement>();

  constructor(name: Key) {
    bind(this.bar, name, { text: false });
    const caption = bind(h("h3", { class: "edit-bar-caption" }), name, { name: false });
    this.root = h("section", { class: "edit-bar" }, caption, this.bar);
  }

  /** A button that runs `fn` on each click: its icon, or its text where it has none; named by `key`. */
  action(key: Key, fn: () => void): HTMLButtonElement {
    const svg = icon(key);
    const b = h("button", { type: "button", class: svg === null ? "text-button" : "icon-button" });
    bind(b, key, { text: svg === null, title: key });
    if (svg !== null) {
      b.append(svg);
    }
    b.addEventListener("click", fn);
    this.bar.append(b);
    return b;
  }

  /** A file input drawn as the icon button of `key` (its label); named by `key`. */
  fileAction(key: Key, input: HTMLInputElement): HTMLLabelElement {
    const svg = icon(key);
    const label = h("label", { class: "icon-button file-button" });
    bind(label, key, { text: false, name: false, title: key });
    if (svg !== null) {
      label.append(svg);
    }
    label.append(input);
    this.bar.append(label);
    return label;
  }

  /** A thin rule between groups of buttons. */
  separator(): void {
    this.bar.append(h("span", { class: "icon-sep", "aria-hidden": "true" }));
  }

  /** A tool's button: a click hands `tool` to `pick` (which calls `press`). */
  tool(tool: T, key: Key, pick: (tool: T) => void): HTMLButtonElement {
    const b = this.action(key, () => pick(tool));
    this.tools.set(tool, b);
    return b;
  }

  /** Show `tool` as the one pressed. */
  press(tool: T): void {
    for (const [k, b] of this.tools) {
      b.setAttribute("aria-pressed", String(k === tool));
    }
  }

  /**
   * The tooltips (guide 5.4): each element's `title` is its tip, and while it is pointed at or focused the tip
   * is shown in `shown` too; after, `current()`'s tip (the chosen tool's).
   */
  tips(pairs: ReadonlyArray<readonly [HTMLElement, Key]>, shown: HTMLElement, current: () => Key): void {
    for (const [el, key] of pairs) {
      bind(el, key, { text: false, name: false, title: key });
      const show = (): void => {
        shown.textContent = t(key);
      };
      const back = (): void => {
        shown.textContent = t(current());
      };
      el.addEventListener("pointerenter", show);
      el.addEventListener("focusin", show);
      el.addEventListener("pointerleave", back);
      el.addEventListener("focusout", back);
    }
  }
}
