/**
 * Label placement on the map view (issue 35): station names and the map's labels (hiddenlabel: room names) drawn
 * without overlap, as map renderers place them: a greedy pass in priority order over a few candidate positions
 * around each anchor, the first free one taken, a label with none free hidden at that zoom.
 *
 * Where they meet the guide says nothing (5.4: "Insert a label to indicate special areas for better understanding
 * the map."): erratum E-GUI-010 records the decision below and the other readings.
 *
 * Rules:
 * - Priority: stations above map labels (a station's name is what a user commands the platform to), each kind in
 *   document order. What is placed first is never moved by what comes later.
 * - Candidates are a table per kind, tried in order. A station keeps its old place first (up and right of its
 *   symbol), then the other corners, then the sides (Imhof's order); a map label keeps its old place first (its
 *   text starting at its point), then centred on the point, then above and below.
 * - Obstacles (the station symbols) are entered before any label: no label covers a station.
 * - Collisions are looked up in a uniform grid of cells over the canvas (`BoxGrid`), so placing n labels costs
 *   about n x candidates x a few boxes, not n^2.
 * - Pure: no canvas here. The caller measures the texts (maprender.ts) and draws what `placeLabels` returns.
 */

/** A box in canvas px: top-left corner, width, height. */
export interface Box {
  x: number;
  y: number;
  w: number;
  h: number;
}

export type LabelKind = "station" | "hiddenlabel";

/** A label to place: its text's size (px) and the point it names (canvas px). */
export interface LabelIn {
  kind: LabelKind;
  text: string;
  /** the anchor: the station's centre, or the map label's point */
  ax: number;
  ay: number;
  /** the text's width and the font's size (px) */
  w: number;
  size: number;
}

/** A label as drawn: its box (canvas px) and where its text starts (fillText's x and baseline y). */
export interface PlacedLabel extends Box {
  kind: LabelKind;
  text: string;
  tx: number;
  ty: number;
}

/** A candidate position: the box's corner at (ax + fx*w + ox, ay + fy*h + oy). */
type Offset = readonly [fx: number, ox: number, fy: number, oy: number];

/** px between a station's centre and its label (its symbol: a 5 px circle and a 12 px heading tick) */
const GAP = 7;
/** a station symbol's half size, as an obstacle (px) */
export const SYMBOL_HALF = 6;
/** the text box: ascent and descent as parts of the font size, and a 1 px pad on each side */
const ASCENT = 0.8;
const DESCENT = 0.25;
const PAD = 1;

export const CANDIDATES: Record<LabelKind, readonly Offset[]> = {
  station: [
    [0, GAP, -1, -GAP], // NE: where it always was
    [0, GAP, 0, GAP], // SE
    [-1, -GAP, -1, -GAP], // NW
    [-1, -GAP, 0, GAP], // SW
    [0, GAP + 2, -0.5, 0], // E
    [-1, -GAP - 2, -0.5, 0], // W
    [-0.5, 0, -1, -GAP - 2], // N
    [-0.5, 0, 0, GAP + 2], // S
  ],
  hiddenlabel: [
    [0, 0, -1, 0], // the text starting at the point, on its baseline: where it always was
    [-0.5, 0, -0.5, 0], // centred
    [-0.5, 0, -1.5, -2], // above
    [-0.5, 0, 0.5, 2], // below
    [-1, 0, -1, 0], // ending at the point
  ],
};

/** Do two boxes overlap (touching edges do not)? */
export function overlaps(a: Box, b: Box): boolean {
  return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

/** Boxes in a uniform grid of `cell` px cells: which of them may meet a box. */
export class BoxGrid {
  private readonly cells = new Map<number, Box[]>();

  constructor(private readonly cell = 64) {}

  private keys(b: Box, fn: (key: number) => boolean | undefined): boolean {
    const c0 = Math.floor(b.x / this.cell),
      c1 = Math.floor((b.x + b.w) / this.cell);
    const r0 = Math.floor(b.y / this.cell),
      r1 = Math.floor((b.y + b.h) / this.cell);
    for (let r = r0; r <= r1; r++) {
      for (let c = c0; c <= c1; c++) {
        // rows and columns of a canvas fit in 16 bits each, a margin either side
        if (fn((r + 0x8000) * 0x10000 + (c + 0x8000)) === true) {
          return true;
        }
      }
    }
    return false;
  }

  add(b: Box): void {
    this.keys(b, (k) => {
      const list = this.cells.get(k);
      if (list === undefined) {
        this.cells.set(k, [b]);
      } else {
        list.push(b);
      }
      return undefined;
    });
  }

  /** Does `b` overlap any box added? */
  hits(b: Box): boolean {
    return this.keys(b, (k) => this.cells.get(k)?.some((o) => overlaps(o, b)) === true);
  }
}

/** The box of a label at a candidate position, and where its text starts. */
export function labelAt(l: LabelIn, [fx, ox, fy, oy]: Offset): PlacedLabel {
  const w = l.w + 2 * PAD;
  const h = (ASCENT + DESCENT) * l.size + 2 * PAD;
  const x = l.ax + fx * w + ox;
  const y = l.ay + fy * h + oy;
  return { kind: l.kind, text: l.text, x, y, w, h, tx: x + PAD, ty: y + PAD + ASCENT * l.size };
}

const RANK: Record<LabelKind, number> = { station: 0, hiddenlabel: 1 };

/** Does a box lie at least partly on a canvas of `width` x `height` px? */
function onCanvas(b: Box, width: number, height: number): boolean {
  return b.x + b.w > 0 && b.y + b.h > 0 && b.x < width && b.y < height;
}

export interface Placement {
  placed: PlacedLabel[];
  /** labels on the canvas that found no free place (hidden at this zoom) */
  hidden: number;
}

/**
 * Place `labels` on a canvas of `width` x `height` px: in priority order (stations first, then map labels, each in
 * the order given), each at its first candidate that overlaps nothing placed before and no obstacle. A label whose
 * candidates all lie off the canvas is left out (neither placed nor hidden).
 */
export function placeLabels(
  labels: readonly LabelIn[],
  obstacles: readonly Box[],
  width: number,
  height: number,
): Placement {
  const grid = new BoxGrid();
  for (const o of obstacles) {
    grid.add(o);
  }
  const order = labels.map((_, i) => i).sort((a, b) => RANK[labels[a].kind] - RANK[labels[b].kind] || a - b);
  const out: Placement = { placed: [], hidden: 0 };
  for (const i of order) {
    const l = labels[i];
    const boxes = CANDIDATES[l.kind].map((c) => labelAt(l, c)).filter((b) => onCanvas(b, width, height));
    if (boxes.length === 0) {
      continue;
    }
    const free = boxes.find((b) => !grid.hits(b));
    if (free === undefined) {
      out.hidden++;
      continue;
    }
    grid.add(free);
    out.placed.push(free);
  }
  return out;
}
