/**
 * Validation before sending (issue 20): a document goes to the platform only when it is valid against the
 * project's XSD (spec/schemas). The browser has no XSD validator, so the gateway validates it with the project's
 * own (spec/documents.py validate_document) at POST api/validate?kind=map|roadmap (gui/validate.py); the answer
 * names the line, which `objectAtLine` turns into the map object to point at on the view.
 */
import type { MapDoc } from "./mapdoc";

export type Verdict = { ok: true } | { ok: false; message: string; line: number | null };

export async function validateDocument(kind: "map" | "roadmap", xml: string): Promise<Verdict> {
  let r: Response;
  try {
    r = await fetch(`api/validate?kind=${kind}`, {
      method: "POST",
      headers: { "Content-Type": "application/xml" },
      body: xml,
    });
  } catch (e) {
    return { ok: false, message: `the document could not be checked: ${(e as Error).message}`, line: null };
  }
  if (!r.ok) {
    return { ok: false, message: `the document could not be checked: HTTP ${r.status} ${await r.text()}`, line: null };
  }
  const v = (await r.json()) as { ok: boolean; message?: string; line?: number | null };
  return v.ok ? { ok: true } : { ok: false, message: v.message ?? "invalid", line: v.line ?? null };
}

/** The ids of the map's objects in the order mapDocToXml writes them (by layer, layers in document order). */
export function writtenOrder(doc: MapDoc): number[] {
  const byLayer = new Map<number, number[]>();
  for (const o of doc.scene.objects) {
    byLayer.set(o.layer, [...(byLayer.get(o.layer) ?? []), o.id]);
  }
  const out: number[] = [];
  const seen = new Set<number>();
  for (const e of doc.entries) {
    if ("layer" in e && !seen.has(e.layer)) {
      seen.add(e.layer);
      out.push(...(byLayer.get(e.layer) ?? []));
    }
  }
  for (const k of [...byLayer.keys()].filter((k) => !seen.has(k)).sort((a, b) => a - b)) {
    out.push(...(byLayer.get(k) ?? []));
  }
  return out;
}

/**
 * The id of the object written at `line` (1-based) of `xml`, the writer's output for `doc` (writeMapDoc puts each
 * object of a layer on its own line, indented four spaces), or null when the line is not an object's.
 */
export function objectAtLine(doc: MapDoc, xml: string, line: number): number | null {
  const order = writtenOrder(doc);
  const lines = xml.split("\n");
  let k = -1;
  let inLayer = false;
  for (let i = 0; i < lines.length && i < line; i++) {
    const s = lines[i];
    if (s.startsWith("  <layer")) {
      inLayer = !s.endsWith("/>");
    } else if (s.startsWith("  </layer")) {
      inLayer = false;
    } else if (inLayer && /^ {4}<[^/!]/.test(s)) {
      k++;
    }
    if (i === line - 1) {
      return inLayer && /^ {4}/.test(s) && k >= 0 ? (order[k] ?? null) : null;
    }
  }
  return null;
}
