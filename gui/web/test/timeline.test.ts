import { describe, expect, it, vi } from "vitest";

// the catalog reads the chosen language at import (i18n.ts); this environment has no localStorage
vi.stubGlobal("localStorage", { getItem: () => null, setItem: () => undefined });
const { clock, thinMarks } = await import("../src/panels/timeline");
const { fromHex } = await import("../src/session/recorded");
const { lastAtOrBefore } = await import("../src/session/recorded_mcap");

describe("the timeline's pure parts", () => {
  it("draws every mark up to the limit, then the first of each slice of the length", () => {
    const events = [0, 0.001, 0.002, 5, 9.999].map((t) => ({ t, name: "CMD_START" }));
    expect(thinMarks(events, 0, 10, 5)).toEqual(events);
    expect(thinMarks(events, 0, 10, 4).map((e) => e.t)).toEqual([0, 5, 9.999]);
  });

  it("says a time as minutes and seconds", () => {
    expect(clock(0)).toBe("0:00.00");
    expect(clock(61.5)).toBe("1:01.50");
    expect(clock(-1)).toBe("0:00.00");
  });

  it("finds the last time at or before a time", () => {
    const times = [10n, 20n, 20n, 30n];
    expect(lastAtOrBefore(times, 5n)).toBe(-1);
    expect(lastAtOrBefore(times, 10n)).toBe(0);
    expect(lastAtOrBefore(times, 25n)).toBe(2);
    expect(lastAtOrBefore(times, 99n)).toBe(3);
    expect(lastAtOrBefore([], 1n)).toBe(-1);
  });

  it("reads a frame's hex", () => {
    expect([...fromHex("ff01fe020000000112")]).toEqual([0xff, 1, 0xfe, 2, 0, 0, 0, 1, 0x12]);
  });
});
