/**
 * The editors' toolbar, one builder for both (guide 5.5: the roadmap's toolbar "looks similar to the toolbar of
 * the map editor"): a `role=toolbar` of buttons named from the message catalog. Actions run once per click; of
 * the tools one at a time is pressed (aria-pressed), the panel deciding what picking one does.
 */
import { h } from "../dom";
import { bind, type Key } from "../i18n/i18n";

export class Toolbar<T extends string> {
  readonly root: HTMLElement = h("div", { role: "toolbar", class: "edit-tools" });
  /** The tools' buttons, in the order they were added. */
  readonly tools = new Map<T, HTMLButtonElement>();

  constructor(name: Key) {
    bind(this.root, name, { text: false });
  }

  /** A button that runs `fn` on each click. */
  action(key: Key, fn: () => void): HTMLButtonElement {
    const b = h("button", { type: "button" });
    bind(b, key);
    b.addEventListener("click", fn);
    this.root.append(b);
    return b;
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
}
