/**
 * Edit -> Edit Map (guide 5.4), a first part: load the platform's map (CMD_GET_MAP), new map, undo and redo,
 * edit objects by drag and drop, add a line, delete, invert a line's direction, send the map to the platform
 * (CMD_SET_MAP). The tool's use is shown at the bottom of the toolbar, as the guide says. The document lives in a
 * History (commands.ts); the map view only draws it and hands the pointer over in its "edit" tool.
 */
import { h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import { type GetMapReply, GetMapRequest, SetMapRequest } from "../pltf";
import type { MapView } from "../panels/mapview";
import type { EditHooks } from "../session/edited";
import type { PlatformSession } from "../session/session";
import { guard } from "../panels/control";
import { toScreen } from "../view/camera";
import {
  addObject,
  addObjects,
  clearMap,
  deleteObjects,
  History,
  invertLine,
  lineOp,
  moveObjects,
  setGeometry,
} from "./commands";
import { clean, extend, orthogonal, parallel, snap, type Pt, type Seg, trim } from "./geometry";
import { newMapDoc, parseMapDoc, sameObjects, writeMapDoc } from "./mapdoc";
import { download, fileInput, fileNameOf } from "./files";
import { Toolbar } from "./toolbar";
import { objectAtLine, validateDocument } from "./validate";
import { LINE_LEN_DEFAULTS, linesFromScan, type ScanStatus } from "./fromscan";
import { SHAPE_TOOLS, type ShapeTool, ShapeTools } from "./drawtools";
import { typedPanel } from "./typedpanel";
import { layerPanel } from "./layerpanel";
import { objectsAt } from "./shapes";
import { askToClose } from "./closeask";
import { applyFields } from "./typed";
import { dialog } from "../ui/dialog";

type RefTool = "trim" | "extend" | "parallel" | "orthogonal";
type EditTool = "select" | "addLine" | RefTool | ShapeTool;
const isShape = (t: EditTool): t is ShapeTool => (SHAPE_TOOLS as readonly string[]).includes(t);
const GRID_MM = 10;
const SNAP_PX = 8;
/** ms after a map is loaded before its spatial index is built (after the first drawing; else at the first click) */
const INDEX_DELAY_MS = 1000;

/** The document's spatial index built a while after it was loaded, off the load's and the first edit's path. */
function indexLater(h: History): void {
  setTimeout(() => h.index(), INDEX_DELAY_MS);
}

/**
 * The object under (x, y) within `tol` mm: the nearest line or vertex (the later on a tie); null when none. The
 * objects near the point come from the history's spatial index (objindex.ts), in document order.
 */
export function hit(h: History, x: number, y: number, tol: number): number | null {
  return objectsAt(h.near(x, y, tol), x, y, tol)[0] ?? null;
}

function nearer(s: Seg, p: Pt): "a" | "b" {
  return Math.hypot(p.x - s.a.x, p.y - s.a.y) <= Math.hypot(p.x - s.b.x, p.y - s.b.y) ? "a" : "b";
}

export function mapEditor(
  session: PlatformSession,
  view: MapView,
  say: (s: string) => void,
  close: () => void = () => undefined,
): { root: HTMLElement; onShow: (shown: boolean) => void } {
  let open = false;
  let history = new History(newMapDoc());
  let tool: EditTool = "select";
  let selected: number | null = null;
  /** several objects selected at once (Select all); empty: the selection is `selected` alone */
  let many = new Set<number>();
  const selection = (): Set<number> => (many.size > 0 ? many : new Set(selected === null ? [] : [selected]));
  const labelIn = h("input", { type: "text", class: "edit-label-text" });
  bind(labelIn, "edit.labelText", { text: false });
  // issue 20: the layer every add tool and the scan conversion put new objects into (layers.ts)
  const layers = layerPanel();
  let drag: { from: Pt; to: Pt; pxPerMm: number } | null = null;
  /** the objects under the last press of "Edit objects", and whether it pressed the one already selected */
  let under: { ids: number[]; again: boolean } = { ids: [], again: false };
  const tip = h("p", { class: "edit-tip", role: "note" });
  bind(tip, "edit.tip", { text: false });
  const state = h("output", { class: "edit-state" });
  const tipFor: Record<EditTool, Key> = {
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
  /** The line clicked first in a two-click tool, and where it was clicked (trim keeps that side). */
  let first: { id: number; at: Pt } | null = null;
  const refOps: Record<RefTool, (s: Seg, r: Seg, at: Pt) => ReturnType<typeof trim>> = {
    trim: (s, r, at) => trim(s, r, at),
    extend: (s, r) => extend(s, r),
    // guide 5.4 "Make lines parallel": turned about the end farther from the click (the click grabs the end to move)
    parallel: (s, r, at) => parallel(s, r, nearer(s, at) === "a" ? "b" : "a"),
    orthogonal: (s, r, at) => orthogonal(s, r, nearer(s, at) === "a" ? "b" : "a"),
  };

  const refresh = (): void => {
    if (open) {
      session.edited.publish({ shows: "map", scene: history.doc.scene, hooks });
    }
    const o = many.size > 0 ? undefined : history.byId(selected);
    state.textContent =
      many.size > 0
        ? t("edit.selectedN", { n: many.size })
        : o === undefined
          ? ""
          : t("edit.selected", { what: `${o.kind} ${o.points.join(", ")}` });
    state.dataset.selectedCount = String(selection().size);
    typed.show(o ?? null);
    state.dataset.objects = String(history.doc.scene.objects.length);
    state.dataset.dirty = String(history.dirty);
    state.dataset.selected = o === undefined ? "" : JSON.stringify({ id: o.id, kind: o.kind, points: o.points });
    layers.update(history.doc);
    undoB.disabled = !history.canUndo;
    redoB.disabled = !history.canRedo;
  };
  const run = (r: { ok: true; value: Parameters<History["run"]>[0] } | { ok: false; reason: string }): void => {
    if (r.ok) {
      history.run(r.value);
      say(r.value.label);
    } else {
      say(r.reason);
    }
    refresh();
  };
  /** the endpoints of the objects within `r` mm of `p` (those the endpoint snap can pick), in document order */
  const endpoints = (p: Pt, r: number): Pt[] => {
    const out: Pt[] = [];
    for (const o of history.near(p.x, p.y, r)) {
      for (let i = 0; i + 1 < o.points.length; i += 2) {
        out.push({ x: o.points[i], y: o.points[i + 1] });
      }
    }
    return out;
  };

  const shapes = new ShapeTools({
    doc: () => history.doc,
    run,
    say,
    snap: (p, pxPerMm) => snap(p, endpoints(p, SNAP_PX / pxPerMm), SNAP_PX / pxPerMm, GRID_MM),
    snapEnd: (p, pxPerMm) => snap(p, endpoints(p, SNAP_PX / pxPerMm), SNAP_PX / pxPerMm, 0),
    near: (x, y, tol) => history.near(x, y, tol),
    labelText: () => labelIn.value,
    layer: () => layers.value(),
    selection,
    measured: (m) => {
      state.dataset.measure = JSON.stringify(m);
      return t("edit.measured", { d: m.distance, dx: m.dx, dy: m.dy, a: m.angle });
    },
    grid: GRID_MM,
  });
  // typed coordinates of the one selected object (typed.ts): mm and degrees, one undoable step
  const typed = typedPanel((input, shown) => {
    const o = history.byId(selected);
    if (o === undefined || many.size > 0) {
      say(t("edit.noneSelected"));
      return;
    }
    const g = applyFields(o, shown, input);
    run(g.ok ? { ok: true, value: setGeometry(history.doc, o.id, g.value) } : g);
  });

  const hooks: EditHooks = {
    down(x, y, pxPerMm, button) {
      if (isShape(tool)) {
        shapes.down(tool, x, y, pxPerMm, button);
        return;
      }
      const p = snap({ x, y }, endpoints({ x, y }, SNAP_PX / pxPerMm), SNAP_PX / pxPerMm, GRID_MM);
      if (tool === "select") {
        // a press keeps the selected object when it is among those under the pointer (to drag it); a click that
        // does not move goes on to the next of them (objects on top of each other: a wall on a polygon's edge)
        const ids = objectsAt(history.near(x, y, SNAP_PX / pxPerMm), x, y, SNAP_PX / pxPerMm);
        const again = many.size === 0 && selected !== null && ids.includes(selected);
        under = { ids, again };
        const id = again ? selected : (ids[0] ?? null);
        if (id === null || !many.has(id)) {
          many = new Set();
          selected = id;
        }
        refresh();
      } else if (tool !== "addLine") {
        const id = hit(history, x, y, SNAP_PX / pxPerMm);
        if (id === null) {
          return;
        }
        if (first === null || first.id === id) {
          first = { id, at: { x, y } };
          selected = id;
          refresh();
        } else {
          const f = first;
          const op = refOps[tool];
          first = null;
          run(lineOp(history.doc, tool, (s, r) => op(s, r, f.at), f.id, id));
        }
        return;
      }
      drag = { from: tool === "select" ? { x, y } : p, to: p, pxPerMm };
    },
    move(x, y) {
      if (isShape(tool)) {
        shapes.move(tool, x, y);
        return;
      }
      if (drag !== null && (tool === "select" || tool === "addLine")) {
        drag.to =
          tool === "select"
            ? { x, y }
            : snap({ x, y }, endpoints({ x, y }, SNAP_PX / drag.pxPerMm), SNAP_PX / drag.pxPerMm, GRID_MM);
      }
    },
    up(x, y) {
      if (isShape(tool)) {
        shapes.up(tool, x, y);
        return;
      }
      const d = drag;
      drag = null;
      if (d === null) {
        return;
      }
      if (tool === "select" && selection().size > 0) {
        const dx = Math.round((x - d.from.x) / GRID_MM) * GRID_MM;
        const dy = Math.round((y - d.from.y) / GRID_MM) * GRID_MM;
        if (dx !== 0 || dy !== 0) {
          run({ ok: true, value: moveObjects(history.doc, selection(), dx, dy) });
        } else if (under.again && under.ids.length > 1 && Math.hypot(x - d.from.x, y - d.from.y) * d.pxPerMm < 3) {
          selected = under.ids[(under.ids.indexOf(selected as number) + 1) % under.ids.length];
          refresh();
        }
      } else if (tool === "addLine") {
        const to = d.to;
        if (Math.hypot(to.x - d.from.x, to.y - d.from.y) < 1) {
          say("the line has zero length");
          return;
        }
        const points = [d.from.x, d.from.y, to.x, to.y].map(clean);
        run({ ok: true, value: addObject(history.doc, { kind: "line", layer: layers.value(), points, attrs: {} }) });
      }
    },
    draw(ctx, cam) {
      ctx.strokeStyle = "#e65100";
      ctx.lineWidth = 3;
      const sel = selection();
      // a few selected: looked up by id (no pass over 50,000 objects per frame); many: in document order
      const drawn =
        sel.size > 16 ? history.doc.scene.objects.filter((o) => sel.has(o.id)) : [...sel].map((id) => history.byId(id));
      for (const o of drawn) {
        if (o === undefined || o.points.length < 2) {
          continue;
        }
        ctx.beginPath();
        for (let i = 0; i + 1 < o.points.length; i += 2) {
          const [sx, sy] = toScreen(cam, o.points[i], o.points[i + 1]);
          if (i === 0) ctx.moveTo(sx, sy);
          else ctx.lineTo(sx, sy);
          if (tool === "vertex") ctx.strokeRect(sx - 3, sy - 3, 6, 6);
        }
        if (o.points.length > 4 && o.kind !== "line") ctx.closePath();
        ctx.stroke();
      }
      if (isShape(tool)) {
        shapes.draw(ctx, cam, tool);
      }
      if (drag !== null && tool === "addLine") {
        const [x0, y0] = toScreen(cam, drag.from.x, drag.from.y);
        const [x1, y1] = toScreen(cam, drag.to.x, drag.to.y);
        ctx.beginPath();
        ctx.moveTo(x0, y0);
        ctx.lineTo(x1, y1);
        ctx.stroke();
      }
      ctx.lineWidth = 1;
    },
  };

  const bar = new Toolbar<EditTool>("edit.tools");
  const act = (key: Key, fn: () => void): HTMLButtonElement => bar.action(key, fn);
  const setTool = (next: EditTool): void => {
    tool = next;
    first = null;
    shapes.cancel();
    bar.press(next);
    bind(tip, tipFor[next], { name: false });
    if (open) {
      view.setTool("edit");
    }
  };
  const loadB = act("edit.load", () => {
    session
      .request(new GetMapRequest())
      .then((r) => {
        const m = r as GetMapReply;
        history = new History(parseMapDoc(m.xml, m.name));
        layers.reset(history.doc);
        indexLater(history);
        selected = null;
        many = new Set();
        say(t("edit.loaded", { n: history.doc.scene.objects.length }));
        refresh();
        view.zoomAll();
      })
      .catch((e: Error) => say(e.message));
  });
  // guide 5.4 "Load a map file from the hard disk of the PC": a malformed file or another kind of document is
  // refused with its reason and the editor keeps its content
  const file = fileInput(".map,.xml,application/xml,text/xml", "edit.open", say, (fileName, text) => {
    try {
      history = new History(parseMapDoc(text, fileName.replace(/\.[^.]*$/, "")));
      layers.reset(history.doc);
      indexLater(history);
    } catch (e) {
      say(t("edit.openFailed", { file: fileName, why: (e as Error).message }));
      return;
    }
    selected = null;
    many = new Set();
    say(t("edit.opened", { file: fileName, n: history.doc.scene.objects.length }));
    refresh();
    view.zoomAll();
  });
  bar.root.append(file);
  const save = (fileName: string): void => {
    download(fileName, writeMapDoc(history.doc));
    history.markSaved();
    say(t("edit.saved", { file: fileName }));
    refresh();
  };
  const saveB = act("edit.save", () => save(fileNameOf(history.doc.scene.name, "map", ".map")));
  // guide 5.4 "Save a map as a new file": the file name asked for; the map keeps it as its name from then on
  const saveAsB = act("edit.saveAs", () => {
    const nameIn = h("input", { type: "text", value: fileNameOf(history.doc.scene.name, "map", ".map") });
    bind(nameIn, "edit.fileName", { text: false });
    nameIn.addEventListener(
      "keydown",
      (e) => e.key === "Enter" && (nameIn.closest(".dialog")?.querySelector("button") as HTMLElement | null)?.click(),
    );
    void dialog("edit.saveAsTitle", nameIn, ["edit.saveAs", "dialog.cancel"]).then((k) => {
      const fileName = fileNameOf(nameIn.value, "map", ".map");
      if (k === 0) {
        history.doc.scene.name = fileName.replace(/\.map$/, "");
        save(fileName);
      }
    });
  });
  const newB = act("edit.new", () => {
    history = new History(newMapDoc());
    layers.reset(history.doc);
    selected = null;
    many = new Set();
    refresh();
  });
  // guide 5.4 "Clear the map": every object removed in one undoable step (what the editor does not know stays)
  const clearB = act("edit.clear", () => {
    selected = null;
    many = new Set();
    run({ ok: true, value: clearMap(history.doc) });
  });
  const undoB = act("edit.undo", () => {
    history.undo();
    refresh();
  });
  const redoB = act("edit.redo", () => {
    history.redo();
    refresh();
  });
  bar.tool("select", "edit.select", setTool);
  bar.tool("vertex", "edit.vertex", setTool);
  bar.tool("addLine", "edit.addLine", setTool);
  for (const k of ["reflector", "circle", "workarea", "prohibit", "hiddenpolygon", "label"] as const) {
    bar.tool(k, `edit.${k}`, setTool);
  }
  const finishB = act("edit.finish", () => finishPolygon());
  for (const k of ["trim", "extend", "parallel", "orthogonal"] as const) {
    bar.tool(k, `edit.${k}`, setTool);
  }
  bar.tool("measure", "edit.measure", setTool);
  // guide 5.4 "Select all objects in map"
  const allB = act("edit.selectAll", () => {
    many = new Set(history.doc.scene.objects.map((o) => o.id));
    selected = null;
    setTool("select");
    refresh();
  });
  const scanB = act("edit.fromScan", () => {
    const st = session.status.last;
    if (st === undefined || st.scan.length === 0) {
      say(t("edit.noScan"));
      return;
    }
    const lens = { ...LINE_LEN_DEFAULTS };
    for (const p of session.params.last?.parameters ?? []) {
      if ((p.key === "MinLineLenAux" || p.key === "MinLineLenMap") && Number.isFinite(Number(p.value))) {
        lens[p.key] = Number(p.value);
      }
    }
    const objs = linesFromScan(st as unknown as ScanStatus, lens, layers.value());
    if (objs.length === 0) {
      say(t("edit.noLines"));
      return;
    }
    run({ ok: true, value: addObjects(history.doc, objs, t("edit.converted", { n: objs.length })) });
  });
  const deleteB = act("edit.delete", () => {
    const ids = selection();
    if (ids.size === 0) {
      say(t("edit.noneSelected"));
      return;
    }
    selected = null;
    many = new Set();
    run({ ok: true, value: deleteObjects(history.doc, ids) });
  });
  const invertB = act("edit.invert", () => {
    if (selected === null) {
      say(t("edit.noneSelected"));
      return;
    }
    run(invertLine(history.doc, selected));
  });
  const sendB = act("edit.send", () => {
    const doc = history.doc;
    let xml: string;
    try {
      xml = writeMapDoc(doc);
    } catch (e) {
      say((e as Error).message);
      return;
    }
    // issue 20: checked against spec/schemas/map.xsd first; an invalid document is not sent, the object is selected
    void validateDocument("map", xml).then((v) => {
      if (!v.ok) {
        selected = v.line === null ? null : objectAtLine(doc, xml, v.line);
        many = new Set();
        say(t("edit.invalid", { why: v.message }));
        refresh();
        return;
      }
      try {
        session.send(new SetMapRequest({ name: doc.scene.name || "edited", xml }));
        history.markSaved();
        say(t("edit.sent", { n: doc.scene.objects.length }));
        refresh();
        // CMD_SET_MAP has no reply: the platform's GET_MAP (answered after it, guide 6.1) says whether it took the map
        session
          .request(new GetMapRequest())
          .then((r) => {
            const got = (r as GetMapReply).xml;
            say(sameObjects(xml, got) ? t("edit.active", { n: doc.scene.objects.length }) : t("edit.notTaken"));
          })
          .catch((e: Error) => say(e.message));
      } catch (e) {
        say((e as Error).message);
      }
    });
  });
  guard(session, sendB); // CMD_SET_MAP: only while this tab may command (issue 33)
  // guide 5.4 "Closes the toolbar and asks for saving if necessary"
  const closeB = act("edit.close", () => {
    const shut = (): void => {
      shapes.cancel();
      close();
      say(t("edit.closed"));
    };
    void askToClose(history.dirty, "edit.closeAsk").then((how) => {
      if (how === "saved") {
        save(fileNameOf(history.doc.scene.name, "map", ".map"));
      } else if (how === "discarded") {
        history = new History(newMapDoc());
        layers.reset(history.doc);
        selected = null;
        many = new Set();
      }
      if (how !== "cancelled") {
        shut();
      }
    });
  });
  const finishPolygon = (): void => {
    if (tool === "workarea" || tool === "prohibit" || tool === "hiddenpolygon") {
      shapes.finish(tool);
      view.setTool("edit"); // redraw without the draft
    }
  };
  // the tooltips at the bottom of the toolbar (guide 5.4): the pointed-at button's use, else the chosen tool's
  const hoverTips: Array<[HTMLElement, Key]> = [
    [loadB, "edit.tipLoad"],
    [file, "edit.tipOpen"],
    [saveB, "edit.tipSave"],
    [saveAsB, "edit.tipSaveAs"],
    [newB, "edit.tipNew"],
    [clearB, "edit.tipClear"],
    [undoB, "edit.tipUndo"],
    [redoB, "edit.tipRedo"],
    [finishB, "edit.tipWorkarea"],
    [allB, "edit.tipSelectAll"],
    [scanB, "edit.tipFromScan"],
    [deleteB, "edit.tipDelete"],
    [invertB, "edit.tipInvert"],
    [sendB, "edit.tipSend"],
    [closeB, "edit.tipClose"],
    ...[...bar.tools].map(([k, b]): [HTMLElement, Key] => [b, tipFor[k]]),
  ];
  for (const [b, key] of hoverTips) {
    bind(b, key, { text: false, name: false, title: key });
    const show = (): void => {
      tip.textContent = t(key);
    };
    const back = (): void => {
      tip.textContent = t(tipFor[tool]);
    };
    b.addEventListener("pointerenter", show);
    b.addEventListener("focus", show);
    b.addEventListener("pointerleave", back);
    b.addEventListener("blur", back);
  }
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
      shapes.cancel();
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
      if (k === "z" && !e.shiftKey) history.undo();
      else history.redo();
      refresh();
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
  const labelField = h("label", { class: "edit-label" }, h("span", {}), labelIn);
  bind(labelField.firstElementChild as HTMLElement, "edit.labelText", { name: false });
  return { root: h("div", { class: "map-editor" }, bar.root, labelField, layers.root, typed.root, state, tip), onShow };
}
