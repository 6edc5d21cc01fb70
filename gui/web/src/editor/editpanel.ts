/**
 * Edit -> Edit Map (guide 5.4), a first part: load the platform's map (CMD_GET_MAP), new map, undo and redo,
 * edit objects by drag and drop, add a line, delete, invert a line's direction, send the map to the platform
 * (CMD_SET_MAP). The tool's use is shown at the bottom of the toolbar, as the guide says. The document lives in a
 * History (commands.ts); the map view only draws it and hands the pointer over in its "edit" tool.
 */
import { h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import { GetMapReply, GetMapRequest, SetMapRequest } from "../pltf";
import type { MapView } from "../panels/mapview";
import type { PlatformSession } from "../session/session";
import { toScreen } from "../view/camera";
import { addObject, addObjects, deleteObjects, History, invertLine, lineOp, moveObjects } from "./commands";
import { clean, extend, orthogonal, parallel, snap, type Pt, type Seg, trim } from "./geometry";
import { newMapDoc, parseMapDoc, writeMapDoc } from "./mapdoc";
import { MAX_XML_CHARS } from "./xml";
import { download, fileNameOf } from "./files";
import { Toolbar } from "./toolbar";
import { objectAtLine, validateDocument } from "./validate";
import { LINE_LEN_DEFAULTS, linesFromScan, type ScanStatus } from "./fromscan";

type EditTool = "select" | "addLine" | "trim" | "extend" | "parallel" | "orthogonal";
type RefTool = Exclude<EditTool, "select" | "addLine">;
const GRID_MM = 10;
const SNAP_PX = 8;

/** The object under (x, y) within `tol` mm: the nearest line or vertex; null when none. */
export function hit(h: History, x: number, y: number, tol: number): number | null {
  let best: number | null = null;
  let bestD = tol;
  for (const o of h.doc.scene.objects) {
    const p = o.points;
    for (let i = 0; i + 1 < p.length; i += 2) {
      const n = p.length >= 4 ? (i + 2) % p.length : i;
      const ax = p[i];
      const ay = p[i + 1];
      const bx = p[n];
      const by = p[n + 1];
      const len2 = (bx - ax) ** 2 + (by - ay) ** 2;
      const u = len2 === 0 ? 0 : Math.max(0, Math.min(1, ((x - ax) * (bx - ax) + (y - ay) * (by - ay)) / len2));
      const d = Math.hypot(x - (ax + u * (bx - ax)), y - (ay + u * (by - ay))) - (o.r ?? 0);
      if (Math.abs(d) <= bestD) {
        bestD = Math.abs(d);
        best = o.id;
      }
    }
  }
  return best;
}

function nearer(s: Seg, p: Pt): "a" | "b" {
  return Math.hypot(p.x - s.a.x, p.y - s.a.y) <= Math.hypot(p.x - s.b.x, p.y - s.b.y) ? "a" : "b";
}

export function mapEditor(
  session: PlatformSession,
  view: MapView,
  say: (s: string) => void,
): { root: HTMLElement; onShow: (shown: boolean) => void } {
  let open = false;
  let history = new History(newMapDoc());
  let tool: EditTool = "select";
  let selected: number | null = null;
  let drag: { from: Pt; to: Pt; pxPerMm: number } | null = null;
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
      view.showScene(history.doc.scene);
    }
    const o = history.doc.scene.objects.find((x) => x.id === selected);
    state.textContent = o === undefined ? "" : t("edit.selected", { what: `${o.kind} ${o.points.join(", ")}` });
    state.dataset.objects = String(history.doc.scene.objects.length);
    state.dataset.dirty = String(history.dirty);
    state.dataset.selected = o === undefined ? "" : JSON.stringify({ id: o.id, kind: o.kind, points: o.points });
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
  const endpoints = (): Pt[] => {
    const out: Pt[] = [];
    for (const o of history.doc.scene.objects) {
      for (let i = 0; i + 1 < o.points.length; i += 2) {
        out.push({ x: o.points[i], y: o.points[i + 1] });
      }
    }
    return out;
  };

  const hooks: NonNullable<MapView["editHooks"]> = {
    down(x, y, pxPerMm) {
      const p = snap({ x, y }, endpoints(), SNAP_PX / pxPerMm, GRID_MM);
      if (tool === "select") {
        selected = hit(history, x, y, SNAP_PX / pxPerMm);
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
      if (drag !== null && (tool === "select" || tool === "addLine")) {
        drag.to = tool === "select" ? { x, y } : snap({ x, y }, endpoints(), SNAP_PX / drag.pxPerMm, GRID_MM);
      }
    },
    up(x, y) {
      const d = drag;
      drag = null;
      if (d === null) {
        return;
      }
      if (tool === "select" && selected !== null) {
        const dx = Math.round((x - d.from.x) / GRID_MM) * GRID_MM;
        const dy = Math.round((y - d.from.y) / GRID_MM) * GRID_MM;
        if (dx !== 0 || dy !== 0) {
          run({ ok: true, value: moveObjects(history.doc, [selected], dx, dy) });
        }
      } else if (tool === "addLine") {
        const to = d.to;
        if (Math.hypot(to.x - d.from.x, to.y - d.from.y) < 1) {
          say("the line has zero length");
          return;
        }
        const points = [d.from.x, d.from.y, to.x, to.y].map(clean);
        run({ ok: true, value: addObject(history.doc, { kind: "line", layer: 0, points, attrs: {} }) });
      }
    },
    draw(ctx, cam) {
      const o = history.doc.scene.objects.find((x) => x.id === selected);
      ctx.strokeStyle = "#e65100";
      ctx.lineWidth = 3;
      if (o !== undefined && o.points.length >= 2) {
        ctx.beginPath();
        for (let i = 0; i + 1 < o.points.length; i += 2) {
          const [sx, sy] = toScreen(cam, o.points[i], o.points[i + 1]);
          if (i === 0) ctx.moveTo(sx, sy);
          else ctx.lineTo(sx, sy);
        }
        ctx.stroke();
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
    bar.press(next);
    bind(tip, tipFor[next], { name: false });
    if (open) {
      view.setTool("edit");
    }
  };
  act("edit.load", () => {
    session
      .request(new GetMapRequest())
      .then((r) => {
        const m = r as GetMapReply;
        history = new History(parseMapDoc(m.xml, m.name));
        selected = null;
        say(t("edit.loaded", { n: history.doc.scene.objects.length }));
        refresh();
        view.zoomAll();
      })
      .catch((e: Error) => say(e.message));
  });
  // guide 5.4 "Load a map file from the hard disk of the PC": a malformed file or another kind of document is
  // refused with its reason and the editor keeps its content
  const file = h("input", { type: "file", accept: ".map,.xml,application/xml,text/xml" });
  bind(file, "edit.open", { text: false });
  file.addEventListener("change", () => {
    const f = file.files?.[0];
    file.value = "";
    if (f === undefined) {
      return;
    }
    if (f.size > MAX_XML_CHARS) {
      say(t("edit.openFailed", { file: f.name, why: `${f.size} bytes is over ${MAX_XML_CHARS}` }));
      return;
    }
    void f.text().then((text) => {
      try {
        history = new History(parseMapDoc(text, f.name.replace(/\.[^.]*$/, "")));
      } catch (e) {
        say(t("edit.openFailed", { file: f.name, why: (e as Error).message }));
        return;
      }
      selected = null;
      say(t("edit.opened", { file: f.name, n: history.doc.scene.objects.length }));
      refresh();
      view.zoomAll();
    });
  });
  bar.root.append(file);
  act("edit.save", () => {
    download(fileNameOf(history.doc.scene.name, "map", ".map"), writeMapDoc(history.doc));
    history.markSaved();
    refresh();
  });
  act("edit.new", () => {
    history = new History(newMapDoc());
    selected = null;
    refresh();
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
  bar.tool("addLine", "edit.addLine", setTool);
  for (const k of ["trim", "extend", "parallel", "orthogonal"] as const) {
    bar.tool(k, `edit.${k}`, setTool);
  }
  act("edit.fromScan", () => {
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
    const objs = linesFromScan(st as unknown as ScanStatus, lens);
    if (objs.length === 0) {
      say(t("edit.noLines"));
      return;
    }
    run({ ok: true, value: addObjects(history.doc, objs, t("edit.converted", { n: objs.length })) });
  });
  act("edit.delete", () => {
    if (selected === null) {
      say(t("edit.noneSelected"));
      return;
    }
    run({ ok: true, value: deleteObjects(history.doc, [selected]) });
    selected = null;
    refresh();
  });
  act("edit.invert", () => {
    if (selected === null) {
      say(t("edit.noneSelected"));
      return;
    }
    run(invertLine(history.doc, selected));
  });
  act("edit.send", () => {
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
        say(t("edit.invalid", { why: v.message }));
        refresh();
        return;
      }
      try {
        session.send(new SetMapRequest({ name: doc.scene.name || "edited", xml }));
        history.markSaved();
        say(t("edit.sent", { n: doc.scene.objects.length }));
        refresh();
      } catch (e) {
        say((e as Error).message);
      }
    });
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
    view.editHooks = shown ? hooks : null;
    view.setTool(shown ? "edit" : "pan");
    if (shown) {
      refresh();
    } else {
      session.refreshDocuments(); // the view shows the platform's map again
    }
  };
  return { root: h("div", { class: "map-editor" }, bar.root, state, tip), onShow };
}
