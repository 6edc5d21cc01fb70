/** The side dock: the GUI's windows (Hardware Monitor, Platform parameters, View Options, ...) as tabs. */
import { h } from "./dom";
import { bind, type Key } from "./i18n/i18n";

export class Dock {
  readonly root: HTMLElement;
  private tabs = h("div", { role: "tablist", class: "dock-tabs" });
  private panes = new Map<string, { tab: HTMLButtonElement; pane: HTMLElement; onShow?: (shown: boolean) => void }>();
  current: string | null = null;

  constructor() {
    bind(this.tabs, "dock.windows", { text: false });
    this.root = h("aside", { class: "dock" }, this.tabs);
  }

  add(id: string, key: Key, content: HTMLElement, onShow?: (shown: boolean) => void): void {
    const tab = h("button", {
      type: "button",
      role: "tab",
      id: `tab-${id}`,
      "aria-controls": `pane-${id}`,
      "aria-selected": "false",
    });
    bind(tab, key);
    const pane = h("section", { role: "tabpanel", id: `pane-${id}`, class: "pane", hidden: true }, content);
    bind(pane, key, { text: false });
    tab.addEventListener("click", () => this.show(id));
    this.tabs.append(tab);
    this.root.append(pane);
    this.panes.set(id, { tab, pane, onShow });
  }

  /** Close a window (its tab stays in the dock to open it again). */
  close(id: string): void {
    const p = this.panes.get(id);
    if (p === undefined || this.current !== id) {
      return;
    }
    p.tab.setAttribute("aria-selected", "false");
    p.pane.hidden = true;
    this.current = null;
    p.onShow?.(false);
  }

  show(id: string): void {
    for (const [k, p] of this.panes) {
      const on = k === id;
      p.tab.setAttribute("aria-selected", String(on));
      p.pane.hidden = !on;
      if (on !== (this.current === k)) {
        p.onShow?.(on);
      }
    }
    this.current = id;
    this.panes
      .get(id)
      ?.pane.querySelector<HTMLElement>("button, input, select, [tabindex]")
      ?.focus({ preventScroll: true });
  }
}
