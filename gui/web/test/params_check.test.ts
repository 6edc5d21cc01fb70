import { describe, expect, it } from "vitest";
import { checkParam } from "../src/params_check";
import { PARAM_BY_NAME, PARAMETERS } from "../src/spec";

const p = (name: string) => PARAM_BY_NAME.get(name)!;

describe("checkParam (from spec/parameters.yaml)", () => {
  it("has the whole table", () => {
    expect(PARAMETERS.length).toBe(104);
  });
  it("accepts values in range and sends canonical text", () => {
    expect(checkParam(p("IpoTransVel"), " 800 ")).toEqual({ ok: true, text: "800" });
    expect(checkParam(p("IpoRotVel"), "0.75")).toEqual({ ok: true, text: "0.75" });
    expect(checkParam(p("PlanningEnabled"), "0")).toEqual({ ok: true, text: "false" });
  });
  it("refuses out of range, wrong type and read-only values with the reason", () => {
    const r = checkParam(p("IpoTransVel"), "5000");
    expect(r.ok).toBe(false);
    expect(!r.ok && r.reason).toContain("outside 50 .. 1500 mm/s");
    expect(checkParam(p("IpoTransVel"), "1.5").ok).toBe(false);
    expect(checkParam(p("IpoRotVel"), "0,6").ok).toBe(false);
    expect(checkParam(p("PlanningEnabled"), "yes").ok).toBe(false);
    const ro = checkParam(p("MaxTransVel"), "1000");
    expect(!ro.ok && ro.reason).toContain("read-only");
  });
});
