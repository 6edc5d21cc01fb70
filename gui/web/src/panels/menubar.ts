/**
 * The menus as chapter 5 names them: Socket (Open Socket, Open Socket At, Close Socket, Shutdown Platform),
 * View (Map, Hardware Monitor, View Options, and the views beyond the original), Parameter (Platform
 * parameters), Edit (the map and roadmap editors of guide 5.4 and 5.5, gui/web/src/editor).
 */
import { h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import { CloseSocketRequest, ExitRequest } from "../pltf";
import type { PlatformSession } from "../session/session";
import { dialog } from "../ui/dialog";

export interface MenuItem {
  key: Key;
  run?: () => void;
  shortcut?: string;
  /** When the item may be used (looked at each time its menu opens and on click): issue 33's commands. */
  enabled?: () => boolean;
}

export function menubar(menus: Array<[Key, MenuItem[]]>): HTMLElement {
  const bar = h("nav", { role: "menubar", class: "menubar" });
  bind(bar, "menu.bar", { text: false });
  const closeAll = () => {
    for (const m of bar.querySelectorAll<HTMLElement>("[role=menu]")) {
      m.hidden = true;
    }
    for (const b of bar.querySelectorAll<HTMLElement>("[aria-haspopup]")) {
      b.setAttribute("aria-expanded", "false");
    }
  };
  const gates: Array<[HTMLElement, () => boolean]> = [];
  for (const [key, items] of menus) {
    const top = h("button", { type: "button", role: "menuitem", "aria-haspopup": "menu", "aria-expanded": "false" });
    bind(top, key);
    const menu = h("div", { role: "menu", class: "menu", hidden: true });
    bind(menu, key, { text: false });
    for (const item of items) {
      const b = h("button", { type: "button", role: "menuitem", "aria-keyshortcuts": item.shortcut ?? false });
      bind(b, item.key);
      if (item.run === undefined) {
        b.setAttribute("aria-disabled", "true");
        b.title = t("menu.nextIssue");
      } else {
        const run = item.run;
        const enabled = item.enabled;
        b.addEventListener("click", () => {
          if (enabled !== undefined && !enabled()) {
            return;
          }
          closeAll();
          run();
        });
        if (enabled !== undefined) {
          gates.push([b, enabled]);
        }
      }
      menu.append(b);
    }
    top.addEventListener("click", () => {
      const open = menu.hidden;
      for (const [b, enabled] of gates) {
        b.setAttribute("aria-disabled", String(!enabled()));
      }
      closeAll();
      menu.hidden = !open;
      top.setAttribute("aria-expanded", String(open));
      if (open) {
        (menu.querySelector("button") as HTMLButtonElement | null)?.focus();
      }
    });
    bar.append(h("div", { class: "menu-root" }, top, menu));
  }
  document.addEventListener("keydown", (e) => e.key === "Escape" && closeAll());
  document.addEventListener("click", (e) => {
    if (!bar.contains(e.target as Node)) {
      closeAll();
    }
  });
  return bar;
}

/** Open Socket At (guide 5.2): the known addresses of Network.ini, or a new one (added to the file). */
export async function openSocketAt(session: PlatformSession, say: (s: string) => void): Promise<void> {
  let known: string[] = [];
  let any = false; // issue 33: a new address only when the gateway was started with --allow-any-target
  try {
    const list = (await (await fetch("api/targets")).json()) as { targets: string[]; any?: boolean };
    known = list.targets;
    any = list.any === true;
  } catch {
    say(t("socket.noList"));
  }
  const select = h("select", {}, ...known.map((k) => h("option", { value: k }, k)));
  select.value = session.target;
  const input = h("input", { type: "text", placeholder: "127.0.0.1:10000" });
  const sel = h("span");
  bind(sel, "socket.server", { name: false });
  bind(select, "socket.server", { text: false });
  const cap = h("span");
  bind(cap, "socket.address", { name: false });
  bind(input, "socket.address", { text: false });
  const hint = h("p", { class: "hint" });
  bind(hint, "socket.onlyKnown", { name: false });
  const body = h(
    "div",
    { class: "form" },
    h("label", { class: "field" }, sel, select),
    any ? h("label", { class: "field" }, cap, input) : hint,
  );
  const choice = await dialog("socket.openAt", body, ["socket.connect", "dialog.cancel"]);
  if (choice !== 0) {
    return;
  }
  const target = input.value.trim() || select.value;
  if (!/^.+:\d{1,5}$/.test(target)) {
    say(t("socket.badAddress", { target }));
    return;
  }
  if (input.value.trim()) {
    fetch("api/targets", {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ target }),
    }).catch(() => undefined);
  }
  localStorage.setItem("pltf.lastTarget", target);
  const url = new URL(window.location.href);
  url.searchParams.set("target", target);
  history.replaceState(null, "", url);
  session.open(target);
}

export async function shutdownPlatform(session: PlatformSession, say: (s: string) => void): Promise<void> {
  const body = h("p");
  bind(body, "socket.shutdownQuestion", { name: false });
  // guide 5.2 "Shutdown connected PlatformControl" = CMD_EXIT "Shuts the platform down" (erratum E-SRV-016)
  if ((await dialog("socket.shutdown", body, ["socket.shutdown", "dialog.cancel"])) === 0) {
    try {
      session.send(new ExitRequest());
      say(t("socket.shutdownSent"));
    } catch (e) {
      say((e as Error).message);
    }
  }
}

export function closeSocket(session: PlatformSession): void {
  // guide 5.2: "The platform will be disconnected. The operation mode of the platform will not be affected."
  session.close(new CloseSocketRequest());
}
