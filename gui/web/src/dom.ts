/** A few DOM helpers: elements with attributes and children, and a labelled value readout. */
import { bind, type Key } from "./i18n/i18n";

export function h<K extends keyof HTMLElementTagNameMap>(
  tag: K,
  attrs: Record<string, string | boolean | number> = {},
  ...children: Array<Node | string>
): HTMLElementTagNameMap[K] {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === false) {
      continue;
    }
    if (k === "class") {
      el.className = String(v);
    } else {
      el.setAttribute(k, v === true ? "" : String(v));
    }
  }
  el.append(...children);
  return el;
}

/** Write `text` only when it differs: an identical write still replaces the text node, and the browser lays out
 * and paints the page again (at 20 status telegrams a second, most of an idle page's work; bench_gui.py). */
export function setText(el: Node, text: string): void {
  if (el.textContent !== text) {
    el.textContent = text;
  }
}

/** A button whose text and accessible name come from the catalog. */
export function button(key: Key, onClick: () => void, attrs: Record<string, string | boolean> = {}): HTMLButtonElement {
  const b = bind(h("button", { type: "button", ...attrs }), key);
  b.addEventListener("click", onClick);
  return b;
}

/** A readout: a caption and an <output> (role status) named by the catalog's `key`. */
export function readout(key: Key, cls = ""): { root: HTMLElement; value: HTMLOutputElement } {
  const caption = bind(h("span", { class: "caption", "aria-hidden": "true" }), key, { name: false });
  const value = h("output", { class: "value" });
  bind(value, key, { text: false });
  return { root: h("div", { class: `readout ${cls}` }, caption, value), value };
}

/** A labelled input: <label>caption <input></label>; the input's name is the caption. */
export function field(key: Key, input: HTMLInputElement | HTMLSelectElement): HTMLLabelElement {
  const caption = h("span");
  const label = h("label", { class: "field" }, caption, input);
  bind(caption, key, { name: false });
  bind(input, key, { text: false });
  return label;
}
