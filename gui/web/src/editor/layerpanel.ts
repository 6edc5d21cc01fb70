/**
 * The map editor's "Layer for new objects" control (layers.ts holds the rules): a select of the document's layer
 * indices and the next free one, "(new layer)" beside an index the document has not got yet. Every add tool and
 * "Convert lines from scan" put their objects into the chosen layer.
 */
import { h } from "../dom";
import { bind, onLanguage, t } from "../i18n/i18n";
import { defaultLayer, layerChoices } from "./layers";
import type { MapDoc } from "./mapdoc";

export function layerPanel(): {
  root: HTMLElement;
  /** the chosen layer */
  value(): number;
  /** the options for `doc` (after an edit, undo or redo); the choice is kept */
  update(doc: MapDoc): void;
  /** a document loaded or started: its first layer chosen */
  reset(doc: MapDoc): void;
} {
  const select = h("select", { class: "edit-layer-select" });
  bind(select, "edit.layerFor", { text: false });
  const caption = h("span", {});
  bind(caption, "edit.layerFor", { name: false });
  const root = h("label", { class: "edit-layer" }, caption, select);
  let chosen = 0;
  /** the options shown, as "index:fresh,..." (the select is rebuilt only when they change) */
  let shown = "";
  let last: MapDoc | null = null;
  select.addEventListener("change", () => {
    chosen = Number(select.value);
  });
  const render = (doc: MapDoc, force: boolean): void => {
    last = doc;
    const choices = layerChoices(doc, chosen);
    const key = choices.map((c) => `${c.index}:${c.fresh ? 1 : 0}`).join(",");
    if (key !== shown || force) {
      shown = key;
      const name = (index: number, fresh: boolean): string =>
        fresh ? t("edit.layerNew", { n: index }) : String(index);
      select.replaceChildren(...choices.map((c) => h("option", { value: c.index }, name(c.index, c.fresh))));
    }
    select.value = String(chosen);
  };
  onLanguage(() => {
    if (last !== null) {
      render(last, true);
    }
  });
  return {
    root,
    value: () => chosen,
    update: (doc) => render(doc, false),
    reset: (doc) => {
      chosen = defaultLayer(doc);
      render(doc, false);
    },
  };
}
