/**
 * The platform as the map view draws and moves it: its geometry from its parameters (guide 5.9 Geometry,
 * UltraSonic) and the pose a drag of the shift or flag tool gives (guide 5.3). Pure functions.
 */
import type { GetPltfParamVecReply } from "../../pltf";
import { type Camera, toWorld } from "../../view/camera";
import { type Footprint, footprint, type Pose, type UsSensor } from "../../view/overlay";

/** A drag as it started: where (canvas px), with which button, and the pose it moves. */
export interface PoseDrag {
  x: number;
  y: number;
  button: number;
  pose: Pose;
}

/** The pose a drag gives: left button moves it, right button turns it toward the pointer (world mm, degrees). */
export function draggedPose(d: PoseDrag, cam: Camera, sx: number, sy: number): Pose {
  const [wx, wy] = toWorld(cam, sx, sy);
  if (d.button === 2) {
    const angle = (Math.atan2(wy - d.pose.y, wx - d.pose.x) * 180) / Math.PI;
    return { ...d.pose, angle: Math.round(angle * 10) / 10 };
  }
  const [w0x, w0y] = toWorld(cam, d.x, d.y);
  return { x: Math.round(d.pose.x + wx - w0x), y: Math.round(d.pose.y + wy - w0y), angle: d.pose.angle };
}

/** The platform's footprint and its 16 ultrasonic sensors; the defaults where a parameter is missing or no number. */
export function platformGeometry(r: Pick<GetPltfParamVecReply, "parameters">): {
  footprint: Footprint;
  usSensors: UsSensor[];
} {
  const v = new Map(r.parameters.map((p) => [p.key, Number(p.value)]));
  const num = (k: string, d: number) => (Number.isFinite(v.get(k)) ? v.get(k)! : d);
  return {
    footprint: footprint(num("PltfLength", 650), num("DistWheels", 430), num("DistPltfCenterToWheelAxis", 100)),
    usSensors: Array.from({ length: 16 }, (_, i) => {
      const n = String(i + 1).padStart(2, "0");
      return { x: num(`USSensor${n}PosX`, 0), y: num(`USSensor${n}PosY`, 0), angle: num(`USSensor${n}Angle`, 0) };
    }),
  };
}
