// The fleet's pure parts (issue 30, session/fleet.ts): which platforms an address lists, the one selected at
// first, names and colours, the status line's data, the body a click hits, the canvas's data-fleet.
import { describe, expect, it } from "vitest";
import {
  bodyAt,
  DocumentOwner,
  drawnFootprint,
  FLEET_COLOURS,
  type FleetBody,
  firstSelected,
  fleetData,
  fleetMembers,
  fleetTargets,
  reach,
  selectedHref,
  statusLine,
} from "../src/session/fleet";
import { footprint } from "../src/view/overlay";
import { GetStatusReply } from "../src/pltf";

const q = (s: string) => new URLSearchParams(s);
const body = (name: string, x: number, y: number, selected = false): FleetBody => ({
  name,
  target: `127.0.0.1:${x}`,
  colour: "#000",
  selected,
  pose: { x, y, angle: 90 },
  footprint: null,
});
const DEFAULT = footprint(650, 430, 100); // rear -425, front 225, half width 270

describe("the fleet of the address", () => {
  it("is every target once, in order; one target is no fleet", () => {
    expect(fleetTargets(q("target=a:1&target=b:2&target=a:1&target=c:3"))).toEqual(["a:1", "b:2", "c:3"]);
    expect(fleetTargets(q("target=a:1"))).toEqual([]);
    expect(fleetTargets(q("target=a:1&target=a:1"))).toEqual([]);
    expect(fleetTargets(q(""))).toEqual([]);
  });

  it("selects ?selected= when it is a member, else the first", () => {
    expect(firstSelected(["a:1", "b:2"], q("selected=b:2"))).toBe("b:2");
    expect(firstSelected(["a:1", "b:2"], q("selected=z:9"))).toBe("a:1");
    expect(firstSelected(["a:1", "b:2"], q(""))).toBe("a:1");
  });

  it("names members from the gateway, else by address; colours in order, repeating past the table", () => {
    const many = Array.from({ length: FLEET_COLOURS.length + 1 }, (_, i) => `h:${i + 1}`);
    const m = fleetMembers(many, [{ name: "alpha", target: "h:2" }]);
    expect(m[0]).toEqual({ target: "h:1", name: "h:1", colour: FLEET_COLOURS[0] });
    expect(m[1].name).toBe("alpha");
    expect(new Set(m.slice(0, FLEET_COLOURS.length).map((x) => x.colour)).size).toBe(FLEET_COLOURS.length);
    expect(m[FLEET_COLOURS.length].colour).toBe(FLEET_COLOURS[0]);
  });

  it("keeps the selection in the address", () => {
    const href = selectedHref("http://127.0.0.1:8080/?target=a:1&target=b:2", "b:2");
    expect(new URL(href).searchParams.get("selected")).toBe("b:2");
    expect(new URL(href).searchParams.getAll("target")).toEqual(["a:1", "b:2"]);
  });
});

describe("a status line", () => {
  const st = Object.assign(new GetStatusReply(), { estX: 4000, estY: -20, estAngle: 90500 });
  st.operationState = 1;
  st.motionMode = 3;

  it("says the state, mode and position while connected", () => {
    expect(statusLine("alpha", true, st)).toEqual({
      name: "alpha",
      connected: true,
      operationState: 1,
      motionMode: 3,
      pose: [4000, -20, 90.5],
    });
  });

  it("says nothing stale when the connection is lost", () => {
    expect(statusLine("alpha", false, st)).toEqual({
      name: "alpha",
      connected: false,
      operationState: null,
      motionMode: null,
      pose: null,
    });
  });
});

describe("the map's bodies", () => {
  const bodies = [body("a", 0, 0, true), body("b", 1000, 0), { ...body("c", 500, 0), pose: null }];

  it("a click hits the nearest body within the radius, never one without a pose", () => {
    expect(bodyAt(bodies, 900, 100, 400)?.name).toBe("b");
    expect(bodyAt(bodies, 100, 0, 400)?.name).toBe("a");
    expect(bodyAt(bodies, 500, 0, 400)).toBeNull();
    expect(bodyAt(bodies, 500, 0, 500)?.name).toBe("a"); // a tie: the first
  });

  it("are written to data-fleet with the footprint drawn, the selected one marked", () => {
    const long = footprint(1600, 900, 100);
    const withOwn = [bodies[0], { ...bodies[1], footprint: long }, bodies[2]];
    expect(fleetData(withOwn, (b) => b.footprint ?? DEFAULT)).toBe(
      "*a@0,0,90.0/-425,225,270;b@1000,0,90.0/-900,700,505;c@-",
    );
  });

  it("a body whose own footprint is not read is drawn with the default one, never the selected platform's", () => {
    const long = footprint(1600, 900, 100); // the session's parameters: the selected platform, a big one
    expect(drawnFootprint(body("watched", 0, 0), long)).toEqual(DEFAULT);
    expect(drawnFootprint(body("chosen", 0, 0, true), long)).toEqual(long); // the session's, until its own is read
    expect(drawnFootprint({ ...body("own", 0, 0), footprint: long }, DEFAULT)).toEqual(long);
  });

  it("a click hits a body within its own footprint's reach (a big platform from farther away)", () => {
    const long = footprint(1600, 900, 100);
    const two = [body("small", 0, 0), { ...body("big", 3000, 0), footprint: long }];
    expect(reach(long)).toBeCloseTo(Math.hypot(900, 505));
    expect(bodyAt(two, 3000 - 950, 0, reach(DEFAULT))?.name).toBe("big"); // within big's 1032 mm
    expect(bodyAt(two, 600, 0, reach(DEFAULT))).toBeNull(); // beyond small's default 507 mm
    expect(bodyAt([{ ...body("small", 0, 0), footprint: DEFAULT }], 600, 0, 5000)).toBeNull(); // its own, not 5 m
  });
});

describe("whose document an editor holds (E-GUI-012)", () => {
  it("is the platform selected when it came, kept over a switch until it is taken again", () => {
    let selected = "a:1";
    const owner = new DocumentOwner(() => selected);
    expect(owner.platform).toBe("a:1");
    expect(owner.elsewhere).toBe(false);
    selected = "b:2"; // a switch: the document stays a:1's
    expect(owner.platform).toBe("a:1");
    expect(owner.elsewhere).toBe(true);
    owner.take(); // loaded from, or sent to, the selected platform
    expect(owner.platform).toBe("b:2");
    expect(owner.elsewhere).toBe(false);
  });
});
