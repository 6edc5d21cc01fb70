// The fleet's pure parts (issue 30, session/fleet.ts): which platforms an address lists, the one selected at
// first, names and colours, the status line's data, the body a click hits, the canvas's data-fleet.
import { describe, expect, it } from "vitest";
import {
  bodyAt,
  FLEET_COLOURS,
  type FleetBody,
  firstSelected,
  fleetData,
  fleetMembers,
  fleetTargets,
  selectedHref,
  statusLine,
} from "../src/session/fleet";
import { GetStatusReply } from "../src/pltf";

const q = (s: string) => new URLSearchParams(s);
const body = (name: string, x: number, y: number, selected = false): FleetBody => ({
  name,
  target: `127.0.0.1:${x}`,
  colour: "#000",
  selected,
  pose: { x, y, angle: 90 },
});

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

  it("are written to data-fleet, the selected one marked", () => {
    expect(fleetData(bodies)).toBe("*a@0,0,90.0;b@1000,0,90.0;c@-");
  });
});
