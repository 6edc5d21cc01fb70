/** The roadmap document (guide 6.5 "Roadmap", 5.5) as plain data: stations, edges and their path points. */

export interface Station {
  id: string;
  name: string;
  x: number;
  y: number;
  /** degrees */
  angle: number;
}

export interface Edge {
  start: string;
  end: string;
  /** the path points between the stations: x0, y0, x1, y1, ... mm */
  points: number[];
}

export interface Roadmap {
  name: string;
  stations: Station[];
  edges: Edge[];
}

export class RoadmapParseError extends Error {}

export function parseRoadmap(xml: string, name = ""): Roadmap {
  if (xml.trim() === "") {
    return { name, stations: [], edges: [] };
  }
  const doc = new DOMParser().parseFromString(xml, "application/xml");
  if (doc.getElementsByTagName("parsererror").length > 0) {
    throw new RoadmapParseError("the roadmap is not well-formed XML");
  }
  if (doc.documentElement.tagName !== "roadmap") {
    throw new RoadmapParseError(`expected a <roadmap> document, got <${doc.documentElement.tagName}>`);
  }
  const stations: Station[] = [];
  for (const s of Array.from(doc.getElementsByTagName("station"))) {
    const p = s.getElementsByTagName("point")[0];
    stations.push({
      id: s.getAttribute("id") ?? s.getAttribute("name") ?? "",
      name: s.getAttribute("name") ?? s.getAttribute("id") ?? "",
      x: Number(p?.getAttribute("x") ?? 0),
      y: Number(p?.getAttribute("y") ?? 0),
      angle: Number(s.getAttribute("angle") ?? 0),
    });
  }
  const edges: Edge[] = [];
  for (const e of Array.from(doc.getElementsByTagName("edge"))) {
    const points: number[] = [];
    for (const p of Array.from(e.getElementsByTagName("point"))) {
      points.push(Number(p.getAttribute("x")), Number(p.getAttribute("y")));
    }
    edges.push({ start: e.getAttribute("startstation") ?? "", end: e.getAttribute("endstation") ?? "", points });
  }
  return { name, stations, edges };
}
