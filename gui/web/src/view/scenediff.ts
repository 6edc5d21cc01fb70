/**
 * What an edit changed in a scene, for the incremental redraw (issue 20): the editor's commands never change an
 * object in place (commands.ts replaces, inserts or removes whole objects), so comparing two object lists by
 * identity finds the one window that differs: a common head, a common tail, and between them the objects of the
 * base that are gone (`start`..`baseEnd`) and those of the current list that are new (`start`..`curEnd`).
 * O(n) pointer compares, no allocation.
 */

export interface ChangedWindow {
  start: number;
  /** end (exclusive) of the base's replaced objects */
  baseEnd: number;
  /** end (exclusive) of the current list's new objects */
  curEnd: number;
}

export function changedWindow(base: readonly unknown[], cur: readonly unknown[]): ChangedWindow {
  const n = Math.min(base.length, cur.length);
  let start = 0;
  while (start < n && base[start] === cur[start]) {
    start++;
  }
  let baseEnd = base.length;
  let curEnd = cur.length;
  while (baseEnd > start && curEnd > start && base[baseEnd - 1] === cur[curEnd - 1]) {
    baseEnd--;
    curEnd--;
  }
  return { start, baseEnd, curEnd };
}

/** How many objects a window touches (the base's removed plus the current's new). */
export function windowSize(w: ChangedWindow): number {
  return w.baseEnd - w.start + (w.curEnd - w.start);
}

/** Per-kind counts of the current list from the base's counts and the window (countKinds without the O(n) pass). */
export function patchCounts(
  baseCounts: Readonly<Record<string, number>>,
  base: readonly { kind: string }[],
  cur: readonly { kind: string }[],
  w: ChangedWindow,
): Record<string, number> {
  const out: Record<string, number> = { ...baseCounts };
  for (let i = w.start; i < w.baseEnd; i++) {
    out[base[i].kind] = (out[base[i].kind] ?? 0) - 1;
  }
  for (let i = w.start; i < w.curEnd; i++) {
    out[cur[i].kind] = (out[cur[i].kind] ?? 0) + 1;
  }
  return out;
}
