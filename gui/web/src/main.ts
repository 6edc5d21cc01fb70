/**
 * PlatformCtrlGUI in the browser (guide ch. 5): the shell that puts the panels together. The session is the only
 * thing that talks to the gateway; every panel subscribes to it and sends through it.
 */
import "./style.css";
import { Dock } from "./dock";
import { h } from "./dom";
import { bind, type Key, onLanguage, t } from "./i18n/i18n";
import { MapView } from "./panels/mapview";
import { closeSocket, menubar, openSocketAt, shutdownPlatform } from "./panels/menubar";
import { motionPanel } from "./panels/motion";
import { operationPanel } from "./panels/operation";
import { statusBar } from "./panels/statusbar";
import { ViewOptions, viewOptionsPanel } from "./panels/viewoptions";
import { PlatformSession } from "./session/session";

const params = new URLSearchParams(window.location.search);
const target = params.get("target") ?? localStorage.getItem("pltf.lastTarget") ?? "";
const wsUrl = new URL("ws", window.location.href);
wsUrl.protocol = wsUrl.protocol === "https:" ? "wss:" : "ws:";
const session = new PlatformSession(wsUrl.href.split("?")[0], target);
const options = new ViewOptions();

const notice = h("p", { class: "notice", role: "status", "aria-live": "polite" });
bind(notice, "app.messages", { text: false });
const say = (text: string) => (notice.textContent = text);

const map = new MapView(session, options);
const dock = new Dock();
dock.add("view-options", "menu.viewOptions", viewOptionsPanel(options));

const menus: Array<[Key, Array<{ key: Key; run?: () => void; shortcut?: string }>]> = [
  ["menu.socket", [
    { key: "menu.openSocket", run: () => session.open(), shortcut: "Control+O" },
    { key: "menu.openSocketAt", run: () => void openSocketAt(session, say) },
    { key: "menu.closeSocket", run: () => closeSocket(session) },
    { key: "menu.shutdownPlatform", run: () => void shutdownPlatform(session, say) },
  ]],
  ["menu.view", [
    { key: "menu.map", run: () => map.canvas.focus() },
    { key: "menu.viewOptions", run: () => dock.show("view-options") },
  ]],
  ["menu.parameter", []],
  ["menu.edit", [{ key: "menu.editMap" }, { key: "menu.editRoadmap" }]],
];

const header = h("header", { class: "top" }, menubar(menus), h("h1", { class: "title" }));
onLanguage(() => {
  header.querySelector("h1")!.textContent = `${t("app.title")} ${session.target}`;
  document.title = t("app.title");
});
const app = document.getElementById("app")!;
app.append(
  header,
  operationPanel(session, say),
  h("main", { class: "workspace" }, h("div", { class: "center" }, map.root, motionPanel(session, map, say)), dock.root),
  notice,
  statusBar(session),
);
dock.show("view-options");
document.addEventListener("keydown", (e) => {
  if (e.ctrlKey && e.key.toLowerCase() === "o") {
    e.preventDefault();
    session.open();
  }
});

// Exposed for the browser tests and the benchmark (read-only use).
(window as unknown as { pltf: unknown }).pltf = { session, map, options, dock };

if (target !== "") {
  localStorage.setItem("pltf.lastTarget", target);
  session.open();
}
