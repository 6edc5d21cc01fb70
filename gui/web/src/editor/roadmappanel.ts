/**
 * Edit -> Edit Roadmap (guide 5.5): "The toolbar for editing the roadmap ... looks similar to the toolbar of the
 * map editor." The roadmap editor's panel: the file actions, Undo and Redo, send-then-verify (CMD_SET_ROADMAP,
 * then CMD_GET_ROADMAP, after checking the document against the project's XSD) and close-with-changes are the
 * document shell's (shell.ts, shellbar.ts); the tools and their state are roadmaptools.ts. This file builds the
 * toolbar and the fields (station name, x, y, angle, Apply) and gives the map view the editor's roadmap (the
 * session's `edited` topic) and its hold on the pointer while the editor is open.
 */
import { button, field, h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import type { EditorFleet } from "../panels/fleet";
import type { MapView } from "../panels/mapview";
import { guard } from "../panels/control";
import { type GetRoadmapReply, GetRoadmapRequest, SetRoadmapRequest } from "../pltf";
import type { EditHooks } from "../session/edited";
import type { PlatformSession } from "../session/session";
import {
  clearRoadmap,
  newRoadmapDoc,
  parseRoadmapDoc,
  RoadmapHistory,
  sameRoadmap,
  writeRoadmapDoc,
} from "./roadmapdoc";
import {
  applyTyped,
  deleteSelected,
  dragMoved,
  drawEditing,
  PRESS,
  type RmTool,
  type RoadmapToolEnv,
  release,
  roadmapEditing,
  run,
  toScene,
} from "./roadmaptools";
import { type DocumentKind, DocumentShell, type PlatformLink } from "./shell";
import { closeButton, fileButtons, historyButtons, pageEffects, type ShellKeys, sendButton, wording } from "./shellbar";
import { act, actionMessage } from "./history";
import { Toolbar } from "./toolbar";
import { validateDocument } from "./validate";

const TIP_FOR: Record<RmTool, Key> = {
  select: "rm.tipSelect",
  addStation: "rm.tipAddStation",
  addEdge: "rm.tipAddEdge",
  pathPoints: "rm.tipPathPoints",
};

const ROADMAP_KEYS: ShellKeys = {
  accept: ".rm,.xml,application/xml,text/xml",
  open: "rm.open",
  new: "rm.new",
  saveAsTitle: "rm.saveAsTitle",
  closeAsk: "rm.closeAsk",
  events: {
    loaded: "rm.loaded",
    opened: "rm.opened",
    openFailed: "edit.openFailed",
    saved: "rm.saved",
    sent: "rm.sent",
    active: "rm.active",
    notTaken: "rm.notTaken",
    invalid: "rm.invalid",
    closed: "rm.closed",
  },
};

/** A roadmap as the shell's document: its reader and writer, roadmap.xsd, compared after sending. */
export const ROADMAP_KIND: DocumentKind<RoadmapHistory> = {
  fallback: "roadmap",
  ext: ".rm",
  parse: (text) => new RoadmapHistory(parseRoadmapDoc(text)),
  blank: () => new RoadmapHistory(newRoadmapDoc()),
  serialise: (history) => writeRoadmapDoc(history.doc),
  validate: (text) => validateDocument("roadmap", text),
  same: sameRoadmap,
  counts: (history) => ({ n: history.doc.stations.length, e: history.doc.edges.length }),
  text: wording(ROADMAP_KEYS),
  action: (said, action) => actionMessage(said, action, t),
};

/** CMD_GET_ROADMAP and CMD_SET_ROADMAP. */
export function roadmapLink(session: PlatformSession): PlatformLink {
  return {
    fetch: () =>
      session
        .request(new GetRoadmapRequest())
        .then((r) => ({ text: (r as GetRoadmapReply).xml, name: (r as GetRoadmapReply).name })),
    send: (name, text) => session.send(new SetRoadmapRequest({ name, xml: text })),
  };
}

function numberField(step: string): HTMLInputElement {
  return h("input", { type: "number", step });
}

export function roadmapEditor(
  session: PlatformSession,
  view: MapView,
  say: (s: string) => void,
  close: () => void = () => undefined,
  fleet: EditorFleet | null = null,
): { root: HTMLElement; onShow: (shown: boolean) => void } {
  let open = false;
  const tip = h("p", { class: "edit-tip", role: "note" });
  bind(tip, "edit.tip", { text: false });
  const state = h("output", { class: "rm-state" });
  const nameIn = h("input", { type: "text" });
  const xIn = numberField("10");
  const yIn = numberField("10");
  const angleIn = numberField("1");
  const bar = new Toolbar<RmTool>("rm.tools");

  const shell: DocumentShell<RoadmapHistory> = new DocumentShell(
    ROADMAP_KIND,
    roadmapLink(session),
    {
      say,
      changed: () => refresh(),
      replaced: () => {
        fleet?.take(); // a fleet: the new document is the selected platform's (erratum E-GUI-012)
        ed.selected = null;
        ed.edgeSel = null;
        refresh();
      },
      close,
    },
    pageEffects(ROADMAP_KEYS),
  );
  const ed = roadmapEditing(() => shell.history);
  const env: RoadmapToolEnv = {
    say,
    text: t,
    refresh: () => refresh(),
    fields: () => ({ name: nameIn.value, angle: angleIn.value }),
  };
  const hooks: EditHooks = {
    down: (x, y, pxPerMm, button) => PRESS[ed.tool](ed, env, x, y, pxPerMm, button),
    move: () => dragMoved(ed),
    up: (x, y) => release(ed, env, x, y),
    draw: (ctx, cam) => drawEditing(ed, ctx, cam),
  };

  const files = fileButtons(shell, bar, ROADMAP_KEYS, say);
  const clearB = bar.action("rm.clear", () => run(ed, env, clearRoadmap, act("act.clearRoadmap"), t("rm.cleared")));
  const undoRedo = historyButtons(shell, bar);
  const refresh = (): void => {
    const doc = shell.history.doc;
    if (open) {
      session.edited.publish({ shows: "roadmap", roadmap: toScene(doc, shell.name), hooks });
    }
    const s = doc.stations.find((x) => x.id === ed.selected);
    state.textContent = s === undefined ? "" : t("edit.selected", { what: `${s.name} (${s.x}, ${s.y}, ${s.angle}°)` });
    state.dataset.stations = String(doc.stations.length);
    state.dataset.edges = String(doc.edges.length);
    state.dataset.dirty = String(shell.history.dirty);
    const e = ed.edgeSel === null ? undefined : doc.edges[ed.edgeSel];
    state.dataset.edge = e === undefined ? "" : JSON.stringify({ start: e.start, end: e.end, points: e.points });
    state.dataset.selected =
      s === undefined ? "" : JSON.stringify({ id: s.id, name: s.name, x: s.x, y: s.y, angle: s.angle });
    if (s !== undefined) {
      nameIn.value = s.name;
      xIn.value = String(s.x);
      yIn.value = String(s.y);
      angleIn.value = String(s.angle);
    }
    undoRedo.update();
  };
  const setTool = (next: RmTool): void => {
    ed.tool = next;
    ed.edgeFrom = null;
    bar.press(next);
    bind(tip, TIP_FOR[next], { name: false });
  };
  bar.separator(); // issue 35: the groups of the toolbar (documents, tools, actions, platform)
  bar.tool("select", "rm.select", setTool);
  bar.tool("addStation", "rm.addStation", setTool);
  bar.tool("addEdge", "rm.addEdge", setTool);
  bar.tool("pathPoints", "rm.pathPoints", setTool);
  const deleteB = bar.action("edit.delete", () => deleteSelected(ed, env));
  const apply = button("rm.apply", () =>
    applyTyped(ed, env, { name: nameIn.value, x: xIn.value, y: yIn.value, angle: angleIn.value }),
  );
  bar.separator();
  const sendB = sendButton(shell, bar, fleet);
  guard(session, sendB); // CMD_SET_ROADMAP: only while this tab may command (issue 33)
  const closeB = closeButton(shell, bar); // guide 5.5 "looks similar to the toolbar of the map editor"
  // guide 5.5 names the buttons of the shell only (its words say "map": read as "roadmap", erratum E-GUI-009)
  const hoverTips: Array<[HTMLElement, Key]> = [
    [files.load, "rm.tipLoad"],
    [files.openButton, "rm.tipOpen"],
    [files.save, "rm.tipSave"],
    [files.saveAs, "rm.tipSaveAs"],
    [files.new, "rm.tipNew"],
    [clearB, "rm.tipClear"],
    [undoRedo.undo, "edit.tipUndo"],
    [undoRedo.redo, "edit.tipRedo"],
    [deleteB, "rm.tipDelete"],
    [apply, "rm.tipApply"],
    [sendB, "rm.tipSend"],
    [closeB, "rm.tipClose"],
    ...[...bar.tools].map(([k, b]): [HTMLElement, Key] => [b, TIP_FOR[k]]),
  ];
  bar.tips(hoverTips, tip, () => TIP_FOR[ed.tool]);
  // every field with its caption (issue 35: they were four bare boxes)
  const fields = h(
    "div",
    { class: "rm-fields" },
    field("rm.stationName", nameIn),
    field("rm.x", xIn),
    field("rm.y", yIn),
    field("rm.angle", angleIn),
    apply,
  );
  // Ctrl+Z / Ctrl+Y (Ctrl+Shift+Z) as in the map editor (ui/icons.ts SHORTCUTS); a text field keeps its own undo
  document.addEventListener("keydown", (e) => {
    const k = e.key.toLowerCase();
    if (!open || !(e.ctrlKey || e.metaKey) || (k !== "z" && k !== "y") || view.tool !== "edit") {
      return;
    }
    if ((e.target as HTMLElement).closest?.("input, select, textarea, .dialog")) {
      return;
    }
    e.preventDefault();
    if (k === "z" && !e.shiftKey) shell.undo();
    else shell.redo();
  });
  setTool("select");
  refresh();
  const onShow = (shown: boolean): void => {
    open = shown;
    if (!shown) {
      session.edited.publish(null);
    }
    view.setTool(shown ? "edit" : "pan");
    if (shown) {
      refresh(); // publishes the document with the editor's hold on the pointer
    } else {
      session.refreshDocuments(); // the view shows the platform's roadmap again
    }
  };
  const parts = [bar.root, fields, state, tip];
  return { root: h("div", { class: "roadmap-editor" }, ...(fleet === null ? [] : [fleet.heading]), ...parts), onShow };
}
