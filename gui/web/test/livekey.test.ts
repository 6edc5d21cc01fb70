import { describe, expect, it } from "vitest";
import { GetStatusReply } from "../src/pltf";
import { liveKey } from "../src/view/livekey";
import type { OverlayOptions } from "../src/view/overlay";

const NONE: OverlayOptions = {
  showEstimated: true,
  showDesired: false,
  scan: false,
  ultrasonic: false,
  path: false,
  localization: false,
  planObstacles: false,
};
const ALL: OverlayOptions = {
  ...NONE,
  showDesired: true,
  scan: true,
  ultrasonic: true,
  path: true,
  localization: true,
  planObstacles: true,
};

function status(init: Partial<GetStatusReply> = {}): GetStatusReply {
  return new GetStatusReply({ estX: 2000, estY: 10000, estAngle: 0, timestamp: 100, ...init });
}

describe("liveKey: what of a status the map draws", () => {
  it("is the same for two statuses that differ only in what the map does not draw", () => {
    const a = status({ timestamp: 100, ioBatteryVoltage: 24000 });
    const b = status({ timestamp: 150, ioBatteryVoltage: 23900 });
    expect(liveKey(b, ALL)).toBe(liveKey(a, ALL));
  });
  it("changes with the estimated pose, whatever is shown", () => {
    expect(liveKey(status({ estX: 2001 }), NONE)).not.toBe(liveKey(status(), NONE));
    expect(liveKey(status({ estAngle: 1 }), NONE)).not.toBe(liveKey(status(), NONE));
  });
  it("changes with a layer's fields only while that layer is shown", () => {
    const cases: Array<[keyof OverlayOptions, Partial<GetStatusReply>]> = [
      ["scan", { scan: [{ x: 1, y: 2 }] }],
      ["ultrasonic", { usDistance: [300, ...Array(15).fill(0)] }],
      ["path", { path: [{ x: 5, y: 6 }] }],
      ["localization", { covMajor: 40 }],
      ["showDesired", { cmdX: 2500 }],
      ["planObstacles", { circles: [{ x: 1, y: 1, radius: 300 }] }],
    ];
    for (const [option, change] of cases) {
      const on = { ...NONE, [option]: true };
      expect(liveKey(status(change), NONE), option).toBe(liveKey(status(), NONE));
      expect(liveKey(status(change), on), option).not.toBe(liveKey(status(), on));
    }
  });
});
