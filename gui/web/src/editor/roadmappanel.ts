/**
 * Edit -> Edit Roadmap (guide 5.5): "The toolbar for editing the roadmap ... looks similar to the toolbar of the
 * map editor." Load the platform's roadmap (CMD_GET_ROADMAP), new, clear, undo and redo, add stations (click on
 * the map; name and angle from the fields), add edges (click two stations), move a station by drag and drop or
 * by typed coordinates (mm, degrees), delete, send to the platform (CMD_SET_ROADMAP) after checking the document
 * against the project's XSD (validate.ts). The view draws the editor's roadmap while the editor is open.
 */
import { h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import { type GetRoadmapReply, GetRoadmapRequest, SetRoadmapRequest } from "../pltf";
import type { MapView } from "../panels/mapview";
import type { Roadmap } from "../scene/roadmap";
import type { EditHooks } from "../session/edited";
import type { PlatformSession } from "../session/session";
import { guard } from "../panels/control";
import { toScreen } from "../view/camera";
import {
  addEdge,
  addStation,
  clearRoadmap,
  deleteStation,
  type Edit,
  moveStation,
  newRoadmapDoc,
  parseRoadmapDoc,
  type RoadmapDoc,
  RoadmapHistory,
  sameRoadmap,
  writeRoadmapDoc,
} from "./roadmapdoc";
import { validateDocument } from "./validate";
import { deletePathPoint, edgeAt, edgePath, insertPathPoint, movePathPoint, pathPointAt } from "./roadmappath";
import { download, fileInput, fileNameOf } from "./files";
import { Toolbar } from "./toolbar";
import { dialog } from "../ui/dialog";
import { askToClose } from "./closeask";

type RmTool = "select" | "addStation" | "addEdge" | "pathPoints";
const GRID_MM = 10;
const HIT_PX = 10;

/** The view's roadmap (scene/roadmap.ts) of the editor's document. */
export function toScene(doc: RoadmapDoc, name: string): Roadmap {
  return {
    name,
    stations: doc.stations.map((s) => ({ id: s.id, name: s.name, x: s.x, y: s.y, angle: s.angle })),
    edges: doc.edges.map((e) => ({ start: e.start, end: e.end, points: [...e.points] })),
  };
}

/** The station nearest (x, y) within `tol` mm, or null. */
export function stationAt(doc: RoadmapDoc, x: number, y: number, tol: number): string | null {
  let best: string | null = null;
  let bestD = tol;
  for (const s of doc.stations) {
    const d = Math.hypot(s.x - x, s.y - y);
    if (d <= bestD) {
      bestD = d;
      best = s.id;
    }
  }
  return best;
}

const grid = (v: number): number => Math.round(v / GRID_MM) * GRID_MM;

function numberField(key: Key, step: string): HTMLInputElement {
  const i = h("input", { type: "number", step });
  bind(i, key, { text: false });
  return i;
}

export function roadmapEditor(
  session: PlatformSession,
  view: MapView,
  say: (s: string) => void,
  close: () => void = () => undefined,
): { root: HTMLElement; onShow: (shown: boolean) => void } {
  let open = false;
  let history = new RoadmapHistory(newRoadmapDoc());
  let name = "";
  let tool: RmTool = "select";
  let selected: string | null = null;
  let edgeFrom: string | null = null;
  let drag: { id: string; moved: boolean } | null = null;
  /** the edge whose path points are edited (its index), and a path point being dragged */
  let edgeSel: number | null = null;
  let pointDrag: { edge: number; k: number; moved: boolean } | null = null;
  const tip = h("p", { class: "edit-tip", role: "note" });
  bind(tip, "edit.tip", { text: false });
  const state = h("output", { class: "rm-state" });
  const nameIn = h("input", { type: "text" });
  bind(nameIn, "rm.stationName", { text: false });
  const xIn = numberField("rm.x", "10");
  const yIn = numberField("rm.y", "10");
  const angleIn = numberField("rm.angle", "1");
  const tipFor: Record<RmTool, Key> = {
    select: "rm.tipSelect",
    addStation: "rm.tipAddStation",
    addEdge: "rm.tipAddEdge",
    pathPoints: "rm.tipPathPoints",
  };

  const refresh = (): void => {
    const doc = history.doc;
    if (open) {
      session.edited.publish({ shows: "roadmap", roadmap: toScene(doc, name), hooks });
    }
    const s = doc.stations.find((x) => x.id === selected);
    state.textContent = s === undefined ? "" : t("edit.selected", { what: `${s.name} (${s.x}, ${s.y}, ${s.angle}°)` });
    state.dataset.stations = String(doc.stations.length);
    state.dataset.edges = String(doc.edges.length);
    state.dataset.dirty = String(history.dirty);
    const e = edgeSel === null ? undefined : doc.edges[edgeSel];
    state.dataset.edge = e === undefined ? "" : JSON.stringify({ start: e.start, end: e.end, points: e.points });
    state.dataset.selected =
      s === undefined ? "" : JSON.stringify({ id: s.id, name: s.name, x: s.x, y: s.y, angle: s.angle });
    if (s !== undefined) {
      nameIn.value = s.name;
      xIn.value = String(s.x);
      yIn.value = String(s.y);
      angleIn.value = String(s.angle);
    }
    undoB.disabled = !history.canUndo;
    redoB.disabled = !history.canRedo;
  };
  const run = (edit: Edit, label: string): string | null => {
    const why = history.run(edit);
    say(why ?? label);
    refresh();
    return why;
  };

  const nameOf = (id: string): string => history.doc.stations.find((st) => st.id === id)?.name ?? id;
  const edgeWords = (k: number): { from: string; to: string; n: number } => {
    const e = history.doc.edges[k];
    return { from: nameOf(e.start), to: nameOf(e.end), n: e.points.length / 2 };
  };
  /** guide 5.5 path points: select an edge, add a point to it, drag a point, right-click deletes it */
  const pathDown = (x: number, y: number, pxPerMm: number, button: number): void => {
    const tol = HIT_PX / pxPerMm;
    const pp = pathPointAt(history.doc, x, y, tol);
    if (pp !== null) {
      edgeSel = pp.edge;
      if (button === 2) {
        if (run(deletePathPoint(pp.edge, pp.k), "") === null) say(t("rm.pathChanged", edgeWords(pp.edge)));
      } else {
        pointDrag = { ...pp, moved: false };
        refresh();
      }
      return;
    }
    const k = edgeAt(history.doc, x, y, tol);
    if (k !== null) {
      edgeSel = k;
      say(t("rm.edgeSelected", edgeWords(k)));
      refresh();
    } else if (edgeSel === null || edgePath(history.doc, edgeSel) === null) {
      say(t("rm.noEdge"));
    } else {
      const sel = edgeSel;
      if (run(insertPathPoint(sel, grid(x), grid(y)), "") === null) say(t("rm.pathChanged", edgeWords(sel)));
    }
  };

  const hooks: EditHooks = {
    down(x, y, pxPerMm, button) {
      if (tool === "pathPoints") {
        pathDown(x, y, pxPerMm, button);
        return;
      }
      const id = stationAt(history.doc, x, y, HIT_PX / pxPerMm);
      if (tool === "addStation") {
        const n = nameIn.value.trim() || `Station_${history.doc.stations.length + 1}`;
        const angle = Number(angleIn.value || "0");
        run(addStation(n, grid(x), grid(y), Number.isFinite(angle) ? angle : 0), t("rm.added", { name: n }));
        selected = history.doc.stations.find((s) => s.name === n)?.id ?? selected;
        refresh();
      } else if (tool === "addEdge") {
        if (id === null) {
          return;
        }
        if (edgeFrom === null || edgeFrom === id) {
          edgeFrom = id;
          selected = id;
          refresh();
        } else {
          const from = edgeFrom;
          edgeFrom = null;
          selected = id;
          run(addEdge(from, id), t("rm.edgeAdded"));
        }
      } else {
        selected = id;
        drag = id === null ? null : { id, moved: false };
        refresh();
      }
    },
    move() {
      if (drag !== null) {
        drag.moved = true;
      }
      if (pointDrag !== null) {
        pointDrag.moved = true;
      }
    },
    up(x, y) {
      const pd = pointDrag;
      pointDrag = null;
      if (pd?.moved) {
        if (run(movePathPoint(pd.edge, pd.k, grid(x), grid(y)), "") === null)
          say(t("rm.pathChanged", edgeWords(pd.edge)));
      }
      const d = drag;
      drag = null;
      if (d?.moved) {
        run(moveStation(d.id, grid(x), grid(y)), t("rm.moved"));
      }
    },
    draw(ctx, cam) {
      const path = tool === "pathPoints" && edgeSel !== null ? edgePath(history.doc, edgeSel) : null;
      if (path !== null) {
        ctx.strokeStyle = "#e65100";
        ctx.lineWidth = 3;
        ctx.beginPath();
        for (let i = 0; i + 1 < path.length; i += 2) {
          const [sx, sy] = toScreen(cam, path[i], path[i + 1]);
          if (i === 0) ctx.moveTo(sx, sy);
          else ctx.lineTo(sx, sy);
          if (i > 0 && i + 2 < path.length) ctx.strokeRect(sx - 4, sy - 4, 8, 8);
        }
        ctx.stroke();
        ctx.lineWidth = 1;
      }
      const s = history.doc.stations.find((x) => x.id === selected);
      if (s !== undefined) {
        const [sx, sy] = toScreen(cam, s.x, s.y);
        ctx.strokeStyle = "#e65100";
        ctx.lineWidth = 3;
        ctx.beginPath();
        ctx.arc(sx, sy, 9, 0, 2 * Math.PI);
        ctx.stroke();
        ctx.lineWidth = 1;
      }
    },
  };

  const bar = new Toolbar<RmTool>("rm.tools");
  const act = (key: Key, fn: () => void): HTMLButtonElement => bar.action(key, fn);
  const setTool = (next: RmTool): void => {
    tool = next;
    edgeFrom = null;
    bar.press(next);
    bind(tip, tipFor[next], { name: false });
  };
  const replace = (doc: RoadmapDoc, newName: string): void => {
    history = new RoadmapHistory(doc);
    name = newName;
    selected = null;
    edgeSel = null;
    refresh();
  };
  act("edit.load", () => {
    session
      .request(new GetRoadmapRequest())
      .then((r) => {
        const m = r as GetRoadmapReply;
        replace(parseRoadmapDoc(m.xml), m.name);
        say(t("rm.loaded", { n: history.doc.stations.length, e: history.doc.edges.length }));
      })
      .catch((e: Error) => say(e.message));
  });
  // guide 5.5 "Load a map from the hard disk": a malformed file or another kind of document is refused with its
  // reason and the editor keeps its roadmap
  const file = fileInput(".rm,.xml,application/xml,text/xml", "rm.open", say, (fileName, text) => {
    try {
      replace(parseRoadmapDoc(text), fileName.replace(/\.[^.]*$/, ""));
    } catch (e) {
      say(t("edit.openFailed", { file: fileName, why: (e as Error).message }));
      return;
    }
    say(t("rm.opened", { file: fileName, n: history.doc.stations.length, e: history.doc.edges.length }));
  });
  bar.root.append(file);
  const save = (fileName: string): void => {
    download(fileName, writeRoadmapDoc(history.doc));
    history.markSaved();
    say(t("rm.saved", { file: fileName }));
    refresh();
  };
  act("edit.save", () => save(fileNameOf(name, "roadmap", ".rm")));
  // guide 5.5 "Save a roadmap as...": the file name asked for; the roadmap keeps it as its name
  act("edit.saveAs", () => {
    const nameIn = h("input", { type: "text", value: fileNameOf(name, "roadmap", ".rm") });
    bind(nameIn, "edit.fileName", { text: false });
    void dialog("rm.saveAsTitle", nameIn, ["edit.saveAs", "dialog.cancel"]).then((k) => {
      if (k === 0) {
        const fileName = fileNameOf(nameIn.value, "roadmap", ".rm");
        name = fileName.replace(/\.rm$/, "");
        save(fileName);
      }
    });
  });
  act("rm.new", () => replace(newRoadmapDoc(), ""));
  act("rm.clear", () => run(clearRoadmap, t("rm.cleared")));
  const undoB = act("edit.undo", () => {
    history.undo();
    refresh();
  });
  const redoB = act("edit.redo", () => {
    history.redo();
    refresh();
  });
  bar.tool("select", "rm.select", setTool);
  bar.tool("addStation", "rm.addStation", setTool);
  bar.tool("addEdge", "rm.addEdge", setTool);
  bar.tool("pathPoints", "rm.pathPoints", setTool);
  act("edit.delete", () => {
    if (selected === null) {
      say(t("edit.noneSelected"));
      return;
    }
    run(deleteStation(selected), t("rm.deleted"));
    selected = null;
    edgeSel = null;
    refresh();
  });
  const apply = act("rm.apply", () => {
    const id = selected;
    if (id === null) {
      say(t("edit.noneSelected"));
      return;
    }
    const [x, y, a] = [Number(xIn.value), Number(yIn.value), Number(angleIn.value || "0")];
    if (![x, y, a].every(Number.isFinite)) {
      say(t("rm.badPose"));
      return;
    }
    const newName = nameIn.value.trim();
    run((doc) => {
      const s = doc.stations.find((st) => st.id === id);
      if (s === undefined) {
        return `no station ${id}`;
      }
      Object.assign(s, { x, y, angle: a, name: newName || s.name });
      return null;
    }, t("rm.moved"));
  });
  const sendB = act("edit.send", () => {
    const xml = writeRoadmapDoc(history.doc);
    void validateDocument("roadmap", xml).then((v) => {
      if (!v.ok) {
        say(t("rm.invalid", { why: v.message }));
        return;
      }
      session.send(new SetRoadmapRequest({ name: name || "edited", xml }));
      history.markSaved();
      const words = { n: history.doc.stations.length, e: history.doc.edges.length };
      say(t("rm.sent", words));
      refresh();
      // CMD_SET_ROADMAP has no reply: GET_ROADMAP after it says whether the platform took the roadmap
      session
        .request(new GetRoadmapRequest())
        .then((r) => say(sameRoadmap(xml, (r as GetRoadmapReply).xml) ? t("rm.active", words) : t("rm.notTaken")))
        .catch((e: Error) => say(e.message));
    });
  });
  guard(session, sendB); // CMD_SET_ROADMAP: only while this tab may command (issue 33)
  // guide 5.5 "looks similar to the toolbar of the map editor": closing asks for saving if necessary
  act("edit.close", () => {
    void askToClose(history.dirty, "rm.closeAsk").then((how) => {
      if (how === "saved") {
        save(fileNameOf(name, "roadmap", ".rm"));
      } else if (how === "discarded") {
        replace(newRoadmapDoc(), "");
      }
      if (how !== "cancelled") {
        close();
        say(t("rm.closed"));
      }
    });
  });
  const fields = h("div", { class: "rm-fields" }, nameIn, xIn, yIn, angleIn, apply);
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
  return { root: h("div", { class: "roadmap-editor" }, bar.root, fields, state, tip), onShow };
}
