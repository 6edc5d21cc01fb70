/**
 * The toolbars' icons (issue 35: the editors' and the map view's): lucide's icons (a kept icon set, ISC licence), only the ones used here so
 * the bundle stays small. A toolbar button shows its icon; its accessible name stays the catalog's words (the
 * guide's names of the tools, 5.4 and 5.5) and its tooltip the guide's description. `ICONS` maps a button's
 * catalog key to its icon; a key without one keeps its text. `SHORTCUTS` lists the editors' keyboard shortcuts
 * for the help overlay.
 */
import {
  ArrowLeftRight,
  ArrowRightToLine,
  Flag,
  Hand,
  Maximize,
  Move,
  RefreshCw,
  ScanSearch,
  ZoomIn,
  ZoomOut,
  Ban,
  Check,
  Circle,
  createElement,
  Download,
  Equal,
  Eraser,
  EyeOff,
  FilePlus,
  FolderOpen,
  type IconNode,
  MapPinPlus,
  MousePointer2,
  PencilLine,
  Radar,
  Redo2,
  Route,
  Ruler,
  Save,
  SavePen,
  ScanLine,
  Scissors,
  Send,
  Spline,
  SplinePointer,
  SquareDashed,
  SquareDashedMousePointer,
  Trash2,
  TriangleRight,
  Type,
  Undo2,
  X,
} from "lucide";
import type { Key } from "../i18n/i18n";
import "./icons.css";

/** The icon of each toolbar button, by the button's catalog key (both editors share the shell's keys). */
export const ICONS: Partial<Record<Key, IconNode>> = {
  "edit.load": Download,
  "edit.open": FolderOpen,
  "rm.open": FolderOpen,
  "edit.save": Save,
  "edit.saveAs": SavePen,
  "edit.new": FilePlus,
  "rm.new": FilePlus,
  "edit.clear": Eraser,
  "rm.clear": Eraser,
  "edit.undo": Undo2,
  "edit.redo": Redo2,
  "edit.select": MousePointer2,
  "rm.select": MousePointer2,
  "edit.vertex": SplinePointer,
  "edit.addLine": PencilLine,
  "edit.reflector": ScanLine,
  "edit.circle": Circle,
  "edit.workarea": SquareDashed,
  "edit.prohibit": Ban,
  "edit.hiddenpolygon": EyeOff,
  "edit.label": Type,
  "edit.finish": Check,
  "edit.trim": Scissors,
  "edit.extend": ArrowRightToLine,
  "edit.parallel": Equal,
  "edit.orthogonal": TriangleRight,
  "edit.measure": Ruler,
  "edit.selectAll": SquareDashedMousePointer,
  "edit.fromScan": Radar,
  "edit.delete": Trash2,
  "edit.invert": ArrowLeftRight,
  "edit.send": Send,
  "edit.close": X,
  "rm.addStation": MapPinPlus,
  "rm.addEdge": Route,
  "rm.pathPoints": Spline,
  // the map view's tools (guide 5.3 Map tools)
  "map.refresh": RefreshCw,
  "map.zoomAll": Maximize,
  "map.zoomIn": ZoomIn,
  "map.zoomOut": ZoomOut,
  "map.zoomArea": ScanSearch,
  "map.pan": Hand,
  "map.shift": Move,
  "map.flag": Flag,
};

/** The icon of `key` as an <svg> hidden from assistive technology (the button carries the name), or null. */
export function icon(key: Key): SVGElement | null {
  const node = ICONS[key];
  if (node === undefined) {
    return null;
  }
  return createElement(node, { "aria-hidden": "true", focusable: "false", class: "icon", width: 18, height: 18 });
}

/** The editors' and the map tools' keyboard shortcuts (editpanel.ts, roadmappanel.ts, map/controller.ts), for the
 * help overlay: keys, what they do and where (catalog keys). */
export const SHORTCUTS: ReadonlyArray<{ keys: string; what: Key; where: Key }> = [
  { keys: "Ctrl+Z", what: "edit.undo", where: "edit.tools" },
  { keys: "Ctrl+Y", what: "edit.redo", where: "edit.tools" },
  { keys: "Ctrl+Shift+Z", what: "edit.redo", where: "edit.tools" },
  { keys: "Enter", what: "edit.finish", where: "edit.tools" },
  { keys: "Escape", what: "edit.cancelDraft", where: "edit.tools" },
  { keys: "R", what: "map.refresh", where: "map.tools" },
  { keys: "+", what: "map.zoomIn", where: "map.tools" },
  { keys: "-", what: "map.zoomOut", where: "map.tools" },
  { keys: "Ctrl+Z", what: "edit.undo", where: "rm.tools" },
  { keys: "Ctrl+Y", what: "edit.redo", where: "rm.tools" },
  { keys: "Ctrl+Shift+Z", what: "edit.redo", where: "rm.tools" },
];
