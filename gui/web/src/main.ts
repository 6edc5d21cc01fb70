/**
 * PlatformCtrlGUI in the browser (guide ch. 5): the shell that puts the panels together. The session is the only
 * thing that talks to the gateway; every panel subscribes to it and sends through it.
 */
import "./style.css";
import { Dock } from "./dock";
import { h } from "./dom";
import { bind, type Key, onLanguage, t } from "./i18n/i18n";
import { GetDebugDataRequest, GetPltfParamVecRequest } from "./pltf";
import { hardwareMonitor } from "./panels/hwmonitor";
import { logPanel } from "./panels/log";
import { MapView } from "./panels/mapview";
import { parametersWindow } from "./panels/params";
import { plotsPanel } from "./panels/plots";
import { wirePanel } from "./panels/wire";
import { mapEditor } from "./editor/editpanel";
import { roadmapEditor } from "./editor/roadmappanel";
import { closeSocket, type MenuItem, menubar, openSocketAt, shutdownPlatform } from "./panels/menubar";
import { motionPanel } from "./panels/motion";
import { operationPanel } from "./panels/operation";
import { statusBar } from "./panels/statusbar";
import { controlPanel } from "./panels/control";
import { ViewOptions, viewOptionsPanel } from "./panels/viewoptions";
import { planObstacleSwitch } from "./panels/planobst";
import { PlatformSession } from "./session/session";
import { RecordedSession } from "./session/recorded";
import { recordedSession } from "./session/recorded_open";
import { mountTimeline } from "./panels/timeline";
import { connText } from "./session/connwords";
import { firstSelected, fleetTargets } from "./session/fleet";
import { editorFleet, type Fleet, fleetPanel } from "./panels/fleet";
import { mountHelp } from "./ui/help";

const params = new URLSearchParams(window.location.search);
// issue 33: the token of the printed URL has become a cookie (gui/doors.py): keep it out of the address bar,
// the history and what a user copies from there
if (params.has("token")) {
  const clean = new URL(window.location.href);
  clean.searchParams.delete("token");
  history.replaceState(null, "", clean);
}
// issue 30: ?target=A&target=B... is a fleet; the panels' one session talks to the selected platform
const fleetList = fleetTargets(params);
const target =
  fleetList.length > 0
    ? firstSelected(fleetList, params)
    : (params.get("target") ?? localStorage.getItem("pltf.lastTarget") ?? "");
const wsUrl = new URL("ws", window.location.href);
wsUrl.protocol = wsUrl.protocol === "https:" ? "wss:" : "ws:";
// issue 35: ?recording=FILE (pltf gui --session) feeds the same panels from a recording instead of a platform
const session = params.has("recording") ? recordedSession() : new PlatformSession(wsUrl.href.split("?")[0], target);
const options = new ViewOptions();

const notice = h("p", { class: "notice", role: "status", "aria-live": "polite" });
bind(notice, "app.messages", { text: false });
const say = (text: string) => (notice.textContent = text);
session.notices.subscribe((ev) => say(connText(ev)));

const map = new MapView(session, options);
const dock = new Dock();
const hw = hardwareMonitor(session, say);
const paramsWin = parametersWindow(session);
const plots = plotsPanel(session);
const wire = wirePanel(session);
dock.add("hardware", "menu.hardwareMonitor", hw.root, hw.onShow);
dock.add("parameters", "menu.platformParameters", paramsWin.root, paramsWin.onShow);
dock.add("view-options", "menu.viewOptions", viewOptionsPanel(options, planObstacleSwitch(session, options, say)));
dock.add("plots", "menu.plots", plots.root, plots.onShow);
dock.add("log", "menu.log", logPanel(session));
dock.add("wire", "menu.wire", wire.root, wire.onShow);
// issue 30: a fleet's status lines; the editors' documents say whose they are (erratum E-GUI-012)
const fleet: Fleet | null =
  fleetList.length > 0 ? fleetPanel(wsUrl.href.split("?")[0], fleetList, target, session, map, () => title()) : null;
const editorSide = (kind: "map" | "roadmap") => (fleet === null ? null : editorFleet(fleet, kind));
const editor = mapEditor(session, map, say, () => dock.close("edit-map"), editorSide("map"));
dock.add("edit-map", "menu.editMap", editor.root, editor.onShow);
const rmEditor = roadmapEditor(session, map, say, () => dock.close("edit-roadmap"), editorSide("roadmap"));
dock.add("edit-roadmap", "menu.editRoadmap", rmEditor.root, rmEditor.onShow);

session.poll("debug", () => new GetDebugDataRequest(), 1);
session.setPolling("debug", true);
session.conn.subscribe((ev) => {
  if (ev.event === "connected") {
    session.request(new GetPltfParamVecRequest()).catch(() => undefined);
  }
});

const menus: Array<[Key, MenuItem[]]> = [
  [
    "menu.socket",
    [
      { key: "menu.openSocket", run: () => session.open(), shortcut: "Control+O" },
      { key: "menu.openSocketAt", run: () => void openSocketAt(session, say) },
      // issue 33: Close Socket ends the link of every tab (refused to a viewer while another tab drives), Shutdown
      // Platform is a command
      {
        key: "menu.closeSocket",
        run: () => closeSocket(session),
        enabled: () => session.drive?.read_only === true || session.mayCommand,
      },
      {
        key: "menu.shutdownPlatform",
        run: () => void shutdownPlatform(session, say),
        enabled: () => session.mayCommand,
      },
    ],
  ],
  [
    "menu.view",
    [
      { key: "menu.map", run: () => map.canvas.focus() },
      { key: "menu.hardwareMonitor", run: () => dock.show("hardware") },
      { key: "menu.viewOptions", run: () => dock.show("view-options") },
      { key: "menu.plots", run: () => dock.show("plots") },
      { key: "menu.log", run: () => dock.show("log") },
      { key: "menu.wire", run: () => dock.show("wire") },
    ],
  ],
  ["menu.parameter", [{ key: "menu.platformParameters", run: () => dock.show("parameters") }]],
  [
    "menu.edit",
    [
      { key: "menu.editMap", run: () => dock.show("edit-map") },
      { key: "menu.editRoadmap", run: () => dock.show("edit-roadmap") },
    ],
  ],
];

const header = h("header", { class: "top" }, menubar(menus), controlPanel(session), h("h1", { class: "title" }));
mountHelp(header); // issue 35: the keyboard shortcuts on ? and the Help button
const title = () => {
  header.querySelector("h1")!.textContent = `${t("app.title")} ${session.target}`;
  document.title = t("app.title");
};
onLanguage(title);
const app = document.getElementById("app")!;
app.append(
  header,
  operationPanel(session, say),
  ...(fleet === null ? [] : [fleet.root]),
  h("main", { class: "workspace" }, h("div", { class: "center" }, map.root, motionPanel(session, map, say)), dock.root),
  notice,
  statusBar(session),
);
dock.show("hardware");
document.addEventListener("keydown", (e) => {
  if (e.ctrlKey && e.key.toLowerCase() === "o") {
    e.preventDefault();
    session.open();
  }
});

// Exposed for the browser tests and the benchmark (read-only use; the map view's surface: MapDebug in mapview.ts).
const pltf = { session, map: map.debug, options, dock, fleet, timeline: null as unknown };
(window as unknown as { pltf: unknown }).pltf = pltf;
if (session instanceof RecordedSession) {
  void mountTimeline(session, app.querySelector("main")!, say).then((tl) => (pltf.timeline = tl));
}

// The optional ground-truth layer: ?control=HOST:PORT names a reference server's control channel (loopback).
const control = params.get("control");
if (control !== null && control !== "") {
  session.watchTruth(control);
}

if (target !== "") {
  if (fleet === null) {
    localStorage.setItem("pltf.lastTarget", target);
  }
  session.open();
}
