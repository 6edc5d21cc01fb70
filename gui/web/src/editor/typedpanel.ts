/**
 * The form for typed coordinates of the selected map object (typed.ts holds the rules): one field per value,
 * named by the catalog ("X1 (mm)", "Direction (degrees)", ...), Apply (or Enter in a field) hands the typed
 * values and the shown ones to `apply`. Hidden while no single object is selected.
 */
import { h } from "../dom";
import { bind, type Key, onLanguage, t } from "../i18n/i18n";
import type { MapObject } from "../scene/map";
import { type Fields, fieldsOf } from "./typed";

function nameOf(k: string): string {
  const m = /^([xy])(\d+)$/.exec(k);
  if (m !== null) {
    return t(m[1] === "x" ? "edit.fx" : "edit.fy", { n: m[2] });
  }
  const keys: Record<string, Key> = {
    r: "edit.fr",
    text: "edit.ftext",
    length: "edit.flength",
    direction: "edit.fdirection",
  };
  return t(keys[k] ?? "edit.coords");
}

export function typedPanel(apply: (input: Fields, shown: Fields) => void): {
  root: HTMLElement;
  show(o: MapObject | null): void;
} {
  const grid = h("div", { class: "edit-coords" });
  const button = h("button", { type: "button" });
  bind(button, "edit.applyCoords");
  const root = h("fieldset", { class: "edit-typed", hidden: true }, grid, button);
  bind(root, "edit.coords", { text: false });
  let shown: Fields = {};
  const inputs = new Map<string, HTMLInputElement>();
  const submit = (): void => {
    const input: Fields = {};
    for (const [k, i] of inputs) {
      input[k] = i.value;
    }
    apply(input, shown);
  };
  button.addEventListener("click", submit);
  const label = (): void => {
    for (const [k, i] of inputs) {
      i.setAttribute("aria-label", nameOf(k));
      i.title = nameOf(k);
      i.previousElementSibling!.textContent = nameOf(k);
    }
  };
  onLanguage(label);
  const show = (o: MapObject | null): void => {
    root.hidden = o === null;
    shown = o === null ? {} : fieldsOf(o);
    grid.replaceChildren();
    inputs.clear();
    for (const [k, v] of Object.entries(shown)) {
      const i = h("input", { type: k === "text" ? "text" : "number", step: "any", value: v });
      i.value = v;
      i.addEventListener("keydown", (e) => {
        if (e.key === "Enter") {
          e.preventDefault();
          submit();
        }
      });
      inputs.set(k, i);
      grid.append(h("label", { class: "edit-coord" }, h("span", {}), i));
    }
    label();
  };
  return { root, show };
}
