/**
 * Edit -> Edit Map (guide 5.4): the map editor's panel. The file actions, Undo and Redo, send-then-verify and
 * close-with-changes are the document shell's (shell.ts, shellbar.ts); the tools and their state are maptools.ts
 * and drawtools.ts. This file builds the toolbar, the fields and the tooltips, and gives the map view the
 * editor's document (the session's `edited` topic) and its hold on the pointer in the view's "edit" tool. The
 * tool's use is shown at the bottom of the toolbar, as the guide says.
 */
import { field, h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import type { EditorFleet } from "../panels/fleet";
import type { MapView } from "../panels/mapview";
import { guard } from "../panels/control";
import { type GetMapReply, GetMapRequest, SetMapRequest } from "../pltf";
import type { EditHooks } from "../session/edited";
import type { PlatformSession } from "../session/session";
import { History } from "./commands";
import { actionMessage } from "./history";
import { ShapeTools } from "./drawtools";
import type { ScanStatus } from "./fromscan";
import { layerPanel } from "./layerpanel";
import { newMapDoc, parseMapDoc, sameObjects, writeMapDoc } from "./mapdoc";
import {
  clearAll,
  convertScan,
  deleteSelection,
  deselect,
  drawEditing,
  type EditTool,
  GRID_MM,
  invertSelected,
  type MapToolEnv,
  mapEditing,
  POINTER,
  run,
  selectAll,
  selection,
  snapped,
  typeCoordinates,
} from "./maptools";
import { type DocumentKind, DocumentShell, type PlatformLink, type Replaced } from "./shell";
import { closeButton, fileButtons, historyButtons, pageEffects, type ShellKeys, sendButton, wording } from "./shellbar";
import { Toolbar } from "./toolbar";
import { typedPanel } from "./typedpanel";
import { objectAtLine, validateDocument } from "./validate";

/** ms after a map is loaded before its spatial index is built (after the first drawing; else at the first click) */
const INDEX_DELAY_MS = 1000;

const TIP_FOR: Record<EditTool, Key> = {
  select: "edit.tipSelect",
  addLine: "edit.tipAddLine",
  trim: "edit.tipTrim",
  extend: "edit.tipExtend",
  parallel: "edit.tipParallel",
  orthogonal: "edit.tipOrthogonal",
  vertex: "edit.tipVertex",
  reflector: "edit.tipReflector",
  circle: "edit.tipCircle",
  workarea: "edit.tipWorkarea",
  prohibit: "edit.tipProhibit",
  hiddenpolygon: "edit.tipHiddenpolygon",
  label: "edit.tipLabel",
  measure: "edit.tipMeasure",
};

const MAP_KEYS: ShellKeys = {
  accept: ".map,.xml,application/xml,text/xml",
  open: "edit.open",
  new: "edit.new",
  saveAsTitle: "edit.saveAsTitle",
  closeAsk: "edit.closeAsk",
  events: {
    loaded: "edit.loaded",
    opened: "edit.opened",
    openFailed: "edit.openFailed",
    saved: "edit.saved",
    sent: "edit.sent",
    active: "edit.active",
    notTaken: "edit.notTaken",
    invalid: "edit.invalid",
    closed: "edit.closed",
  },
};

/** A map as the shell's document: the editor's reader and writer, map.xsd, the objects compared after sending. */
export const MAP_KIND: DocumentKind<History> = {
  fallback: "map",
  ext: ".map",
  parse: (text, name) => new History(parseMapDoc(text, name)),
  blank: () => new History(newMapDoc()),
  serialise: (history) => writeMapDoc(history.doc),
  validate: (text) => validateDocument("map", text),
  same: sameObjects,
  counts: (history) => ({ n: history.doc.scene.objects.length }),
  text: wording(MAP_KEYS),
  action: (said, action) => actionMessage(said, action, t),
  named: (history, name) => {
    history.doc.scene.name = name;
  },
};

/** CMD_GET_MAP and CMD_SET_MAP. */
export function mapLink(session: PlatformSession): PlatformLink {
  return {
    fetch: () =>
      session
        .request(new GetMapRequest())
        .then((r) => ({ text: (r as GetMapReply).xml, name: (r as GetMapReply).name })),
    send: (name, text) => session.send(new SetMapRequest({ name, xml: text })),
  };
}

export function mapEditor(
  session: PlatformSession,
  view: MapView,
  say: (s: string) => void,
  close: () => void = () => undefined,
  fleet: EditorFleet | null = null,
): { root: HTMLElement; onShow: (shown: boolean) => void } {
  let open = false;
  const labelIn = h("input", { type: "text", class: "edit-label-text" });
  bind(labelIn, "edit.labelText", { text: false });
  // issue 20: the layer every add tool and the scan conversion put new objects into (layers.ts)
  const layers = layerPanel();
  const tip = h("p", { class: "edit-tip", role: "note" });
  bind(tip, "edit.tip", { text: false });
  const state = h("output", { class: "edit-state" });
  const bar = new Toolbar<EditTool>("edit.tools");

  const replaced = (how: Replaced): void => {
    fleet?.take(); // a fleet: the new document is the selected platform's (erratum E-GUI-012)
    layers.reset(shell.history.doc);
    if (how !== "new") {
      const loaded = shell.history;
      setTimeout(() => loaded.index(), INDEX_DELAY_MS); // off the load's and the first edit's path
    }
    deselect(ed);
    refresh();
    if (how !== "new") {
      view.zoomAll();
    }
  };
  const shell: DocumentShell<History> = new DocumentShell(
    MAP_KIND,
    mapLink(session),
    {
      say,
      changed: () => refresh(),
      replaced,
      // issue 20: an invalid document is not sent; the object of the line the XSD names is selected
      invalid: (v, xml, history) => {
        ed.selected = v.line === null ? null : objectAtLine(history.doc, xml, v.line);
        ed.many = new Set();
      },
      close: () => {
        env.shapes.cancel();
        close();
      },
    },
    pageEffects(MAP_KEYS),
  );
  const ed = mapEditing(() => shell.history);
  const env: MapToolEnv = {
    say,
    text: t,
    refresh: () => refresh(),
    layer: () => layers.value(),
    shapes: new ShapeTools({
      doc: () => shell.history.doc,
      run: (r) => run(ed, env, r),
      say,
      snap: (p, pxPerMm) => snapped(shell.history, p, pxPerMm),
      snapEnd: (p, pxPerMm) => snapped(shell.history, p, pxPerMm, 0),
      near: (x, y, tol) => shell.history.near(x, y, tol),
      labelText: () => labelIn.value,
      layer: () => layers.value(),
      selection: () => selection(ed),
      measured: (m) => {
        state.dataset.measure = JSON.stringify(m);
        return t("edit.measured", { d: m.distance, dx: m.dx, dy: m.dy, a: m.angle });
      },
      grid: GRID_MM,
    }),
  };
  const typed = typedPanel((input, shown) => typeCoordinates(ed, env, input, shown));
  const hooks: EditHooks = {
    down: (x, y, pxPerMm, button) => POINTER[ed.tool].down(ed, env, x, y, pxPerMm, button),
    move: (x, y) => POINTER[ed.tool].move(ed, env, x, y),
    up: (x, y) => POINTER[ed.tool].up(ed, env, x, y),
    draw: (ctx, cam) => drawEditing(ed, env, ctx, cam),
  };

  const files = fileButtons(shell, bar, MAP_KEYS, say);
  const clearB = bar.action("edit.clear", () => clearAll(ed, env));
  const undoRedo = historyButtons(shell, bar);
  const refresh = (): void => {
    const history = shell.history;
    if (open) {
      session.edited.publish({ shows: "map", scene: history.doc.scene, hooks });
    }
    const o = ed.many.size > 0 ? undefined : history.byId(ed.selected);
    state.textContent =
      ed.many.size > 0
        ? t("edit.selectedN", { n: ed.many.size })
        : o === undefined
          ? ""
          : t("edit.selected", { what: `${o.kind} ${o.points.join(", ")}` });
    state.dataset.selectedCount = String(selection(ed).size);
    typed.show(o ?? null);
    state.dataset.objects = String(history.doc.scene.objects.length);
    state.dataset.dirty = String(history.dirty);
    state.dataset.selected = o === undefined ? "" : JSON.stringify({ id: o.id, kind: o.kind, points: o.points });
    layers.update(history.doc);
    undoRedo.update();
  };
  const setTool = (next: EditTool): void => {
    ed.tool = next;
    ed.first = null;
    env.shapes.cancel();
    bar.press(next);
    bind(tip, TIP_FOR[next], { name: false });
    if (open) {
      view.setTool("edit");
    }
  };
  const finishPolygon = (): void => {
    if (ed.tool === "workarea" || ed.tool === "prohibit" || ed.tool === "hiddenpolygon") {
      env.shapes.finish(ed.tool);
      view.setTool("edit"); // redraw without the draft
    }
  };
  bar.separator(); // issue 35: the groups of the toolbar (documents, tools, actions, platform)
  bar.tool("select", "edit.select", setTool);
  bar.tool("vertex", "edit.vertex", setTool);
  bar.tool("addLine", "edit.addLine", setTool);
  for (const k of ["reflector", "circle", "workarea", "prohibit", "hiddenpolygon", "label"] as const) {
    bar.tool(k, `edit.${k}`, setTool);
  }
  const finishB = bar.action("edit.finish", finishPolygon);
  for (const k of ["trim", "extend", "parallel", "orthogonal"] as const) {
    bar.tool(k, `edit.${k}`, setTool);
  }
  bar.tool("measure", "edit.measure", setTool);
  bar.separator();
  const allB = bar.action("edit.selectAll", () => {
    selectAll(ed);
    setTool("select");
    refresh();
    say(t("edit.selectedN", { n: selection(ed).size })); // issue 35: a message for every action
  });
  const scanB = bar.action("edit.fromScan", () =>
    convertScan(
      ed,
      env,
      session.status.last as unknown as ScanStatus | undefined,
      session.params.last?.parameters ?? [],
    ),
  );
  const deleteB = bar.action("edit.delete", () => deleteSelection(ed, env));
  const invertB = bar.action("edit.invert", () => invertSelected(ed, env));
  bar.separator();
  const sendB = sendButton(shell, bar, fleet);
  guard(session, sendB); // CMD_SET_MAP: only while this tab may command (issue 33)
  const closeB = closeButton(shell, bar);
  // the tooltips at the bottom of the toolbar (guide 5.4): the pointed-at button's use, else the chosen tool's
  const hoverTips: Array<[HTMLElement, Key]> = [
    [files.load, "edit.tipLoad"],
    [files.openButton, "edit.tipOpen"],
    [files.save, "edit.tipSave"],
    [files.saveAs, "edit.tipSaveAs"],
    [files.new, "edit.tipNew"],
    [clearB, "edit.tipClear"],
    [undoRedo.undo, "edit.tipUndo"],
    [undoRedo.redo, "edit.tipRedo"],
    [finishB, "edit.tipWorkarea"],
    [allB, "edit.tipSelectAll"],
    [scanB, "edit.tipFromScan"],
    [deleteB, "edit.tipDelete"],
    [invertB, "edit.tipInvert"],
    [sendB, "edit.tipSend"],
    [closeB, "edit.tipClose"],
    ...[...bar.tools].map(([k, b]): [HTMLElement, Key] => [b, TIP_FOR[k]]),
  ];
  bar.tips(hoverTips, tip, () => TIP_FOR[ed.tool]);
  document.addEventListener("keydown", (e) => {
    if (
      !open ||
      view.tool !== "edit" ||
      e.ctrlKey ||
      e.metaKey ||
      (e.target as HTMLElement).closest?.("input, select, .dialog")
    ) {
      return;
    }
    if (e.key === "Enter") {
      finishPolygon();
    } else if (e.key === "Escape") {
      env.shapes.cancel();
      view.setTool("edit");
    }
  });
  document.addEventListener("keydown", (e) => {
    if (!open || !(e.ctrlKey || e.metaKey) || view.tool !== "edit") {
      return;
    }
    const k = e.key.toLowerCase();
    if (k === "z" || k === "y") {
      e.preventDefault();
      if (k === "z" && !e.shiftKey) shell.undo();
      else shell.redo();
    }
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
      session.refreshDocuments(); // the view shows the platform's map again
    }
  };
  const labelField = field("edit.labelText", labelIn);
  labelField.classList.add("edit-label");
  const parts = [bar.root, labelField, layers.root, typed.root, state, tip];
  return { root: h("div", { class: "map-editor" }, ...(fleet === null ? [] : [fleet.heading]), ...parts), onShow };
}
