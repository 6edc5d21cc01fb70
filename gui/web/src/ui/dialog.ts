/**
 * Shared widgets that belong to no one panel: the modal dialog used by the socket menu (Open Socket At,
 * Shutdown Platform) and by the editors (close with changes, save as). Panels and editors import it from here.
 */
import { h } from "../dom";
import { bind, type Key } from "../i18n/i18n";

/** A modal dialog with a title, a body and buttons; resolves with the chosen button's index (or -1). */
export function dialog(title: Key, body: HTMLElement, buttons: Key[]): Promise<number> {
  return new Promise((resolve) => {
    const d = h("div", { role: "dialog", "aria-modal": "true", class: "dialog" });
    bind(d, title, { text: false });
    const heading = h("h2");
    bind(heading, title, { name: false });
    const row = h("div", { class: "buttons" });
    const done = (i: number) => {
      d.remove();
      resolve(i);
    };
    buttons.forEach((key, i) => {
      const b = h("button", { type: "button" });
      bind(b, key);
      b.addEventListener("click", () => done(i));
      row.append(b);
    });
    d.addEventListener("keydown", (e) => e.key === "Escape" && done(-1));
    d.append(heading, body, row);
    document.body.append(d);
    (d.querySelector("input, select, button") as HTMLElement | null)?.focus();
  });
}
