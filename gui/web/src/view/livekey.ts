/**
 * What of a status telegram the map view draws, as one comparable key: a status whose key equals the last drawn
 * one changes nothing on the map, so the view does not redraw for it (issue 19: at 20 Hz a full redraw of the
 * canvas for an idle platform cost the page a quarter of its main thread and delayed the replies behind it).
 * The fields follow ``drawStatus`` (overlay.ts): the estimated pose always (everything live is placed by it),
 * the rest only where its overlay is shown.
 */
import type { GetStatusReply } from "../pltf";
import type { OverlayOptions } from "./overlay";

type Fields = (s: GetStatusReply) => unknown[];

/** Per overlay option, the status fields its drawing reads (a table, in the order drawStatus draws). */
const DRAWN: Array<[keyof OverlayOptions, Fields]> = [
  ["path", (s) => s.path.flatMap((p) => [p.x, p.y])],
  ["scan", (s) => s.scan.flatMap((p) => [p.x, p.y])],
  ["ultrasonic", (s) => [...s.usDistance]],
  [
    "planObstacles",
    (s) => [
      ...s.lines.flatMap((l) => [l.sourceX, l.sourceY, l.targetX, l.targetY]),
      "c",
      ...s.circles.flatMap((c) => [c.x, c.y, c.radius]),
    ],
  ],
  ["localization", (s) => [s.covMajor, s.covMinor, s.covAxisAngle]],
  ["showDesired", (s) => [s.cmdX, s.cmdY, s.cmdAngle]],
];

export function liveKey(s: GetStatusReply, o: OverlayOptions): string {
  const parts: unknown[] = [s.estX, s.estY, s.estAngle];
  for (const [option, fields] of DRAWN) {
    parts.push(o[option] ? `${option}:${fields(s).join(",")}` : "-");
  }
  return parts.join("|");
}
