/**
 * View options (guide 5.7, figure 8): Platform (center platform, show desired pose, show estimated pose), Grid,
 * Localization, Planning, Map (layers), Language. The options are plain data with a `changed` topic; the panel
 * edits them. The language is switched at once (the original needed a restart).
 */
import { h } from "../dom";
import { bind, language, type Key, type Lang, onLanguage, setLanguage } from "../i18n/i18n";
import { KINDS } from "../scene/map";
import { Topic } from "../session/bus";

export class ViewOptions {
  centerPlatform = false;
  showDesired = true;
  showEstimated = true;
  /** the true pose from the control channel, when the GUI reads one (gui/truth.py) */
  truth = true;
  grid = true;
  localization = true;
  ultrasonic = true;
  planning = true;
  /** the platform's ViewPlanObstEnabled as last read (planobst.ts, erratum E-GUI-005) */
  planObstacles = false;
  mapLayers: Record<string, boolean> = Object.fromEntries([...KINDS, "map", "roadmap"].map((k) => [k, true]));
  readonly changed = new Topic<void>();
}

type Flag =
  | "centerPlatform"
  | "showDesired"
  | "showEstimated"
  | "truth"
  | "grid"
  | "localization"
  | "ultrasonic"
  | "planning";

export function viewOptionsPanel(o: ViewOptions, ...planning: HTMLElement[]): HTMLElement {
  const check = (key: Key, get: () => boolean, set: (v: boolean) => void) => {
    const input = h("input", { type: "checkbox" });
    input.checked = get();
    input.addEventListener("change", () => {
      set(input.checked);
      o.changed.publish();
    });
    const caption = h("span");
    bind(caption, key, { name: false });
    bind(input, key, { text: false });
    return h("label", { class: "check" }, input, caption);
  };
  const flag = (key: Key, name: Flag) =>
    check(
      key,
      () => o[name],
      (v) => (o[name] = v),
    );
  const group = (key: Key, ...items: HTMLElement[]) => {
    const legend = h("legend");
    bind(legend, key, { name: false });
    const fs = h("fieldset", {}, legend, ...items);
    return fs;
  };
  const langs: Array<[Lang, Key]> = [
    ["en", "opt.english"],
    ["de", "opt.german"],
  ];
  const langGroup = group(
    "opt.language",
    ...langs.map(([lang, key]) => {
      const input = h("input", { type: "radio", name: "language", value: lang });
      onLanguage(() => (input.checked = language() === lang));
      input.addEventListener("change", () => input.checked && setLanguage(lang));
      const caption = h("span");
      bind(caption, key, { name: false });
      bind(input, key, { text: false });
      return h("label", { class: "check" }, input, caption);
    }),
  );
  langGroup.setAttribute("role", "radiogroup");
  bind(langGroup, "opt.language", { text: false });
  const root = h(
    "div",
    { class: "view-options" },
    group(
      "opt.platform",
      flag("opt.centerPlatform", "centerPlatform"),
      flag("opt.showDesired", "showDesired"),
      flag("opt.showEstimated", "showEstimated"),
      flag("opt.truth", "truth"),
    ),
    group("opt.grid", flag("opt.showGrid", "grid")),
    group("opt.localization", flag("opt.scan", "localization"), flag("opt.ultrasonic", "ultrasonic")),
    group("opt.planning", flag("opt.path", "planning"), ...planning),
    group(
      "opt.map",
      ...["map", "roadmap", ...KINDS].map((k) =>
        check(
          `kind.${k}` as Key,
          () => o.mapLayers[k],
          (v) => (o.mapLayers[k] = v),
        ),
      ),
    ),
    langGroup,
  );
  return root;
}
