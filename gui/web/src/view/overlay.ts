/**
 * The live layer of the map view, drawn every frame over the cached static layer (guide 5.3): the platform at
 * the estimated and the desired pose, the laser scan, the ultrasonic readings, the interpolated path, the
 * obstacles used for planning, the target flag and a selection rectangle.
 */
import type { GetStatusReply } from "../pltf";
import { type Camera, toScreen } from "./camera";

export interface Pose {
  x: number; // mm
  y: number; // mm
  angle: number; // degrees
}

export interface Footprint {
  /** box in the platform frame, mm: x from rear to front, half width */
  rear: number;
  front: number;
  halfWidth: number;
}

/** errata E-MOT (footprint): PltfLength long, DistWheels + 110 wide, centre DistPltfCenterToWheelAxis behind the axis. */
export function footprint(length: number, distWheels: number, centreToAxis: number): Footprint {
  return { rear: -centreToAxis - length / 2, front: -centreToAxis + length / 2, halfWidth: (distWheels + 110) / 2 };
}

/** A platform whose parameters are not read yet: PltfLength 650, DistWheels 430, DistPltfCenterToWheelAxis 100 mm
 * (their defaults, panels/map/platform.ts `platformGeometry`). */
export const DEFAULT_FOOTPRINT = footprint(650, 430, 100);

export interface UsSensor {
  x: number;
  y: number;
  angle: number; // deg
}

export interface OverlayOptions {
  showEstimated: boolean;
  showDesired: boolean;
  scan: boolean;
  ultrasonic: boolean;
  path: boolean;
  localization: boolean;
  planObstacles: boolean;
}

export function poseToWorld(p: Pose, lx: number, ly: number): [number, number] {
  const a = (p.angle * Math.PI) / 180;
  return [p.x + lx * Math.cos(a) - ly * Math.sin(a), p.y + lx * Math.sin(a) + ly * Math.cos(a)];
}

export function drawPlatform(
  ctx: CanvasRenderingContext2D,
  cam: Camera,
  p: Pose,
  fp: Footprint,
  color: string,
  dashed: boolean,
): void {
  const corners: Array<[number, number]> = [
    [fp.rear, -fp.halfWidth],
    [fp.front, -fp.halfWidth],
    [fp.front, fp.halfWidth],
    [fp.rear, fp.halfWidth],
  ];
  ctx.strokeStyle = color;
  ctx.lineWidth = 2;
  ctx.setLineDash(dashed ? [5, 4] : []);
  ctx.beginPath();
  corners.forEach(([lx, ly], i) => {
    const [sx, sy] = toScreen(cam, ...poseToWorld(p, lx, ly));
    if (i === 0) {
      ctx.moveTo(sx, sy);
    } else {
      ctx.lineTo(sx, sy);
    }
  });
  ctx.closePath();
  ctx.stroke();
  const [cx, cy] = toScreen(cam, p.x, p.y);
  const [hx, hy] = toScreen(cam, ...poseToWorld(p, Math.max(fp.front, 300), 0));
  ctx.beginPath();
  ctx.moveTo(cx, cy);
  ctx.lineTo(hx, hy);
  ctx.stroke();
  ctx.setLineDash([]);
}

export function drawFlag(ctx: CanvasRenderingContext2D, cam: Camera, p: Pose): void {
  const [x, y] = toScreen(cam, p.x, p.y);
  const a = (p.angle * Math.PI) / 180;
  ctx.strokeStyle = "#d50000";
  ctx.fillStyle = "#d50000";
  ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.moveTo(x, y);
  ctx.lineTo(x, y - 26);
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(x, y - 26);
  ctx.lineTo(x + 14, y - 21);
  ctx.lineTo(x, y - 16);
  ctx.fill();
  ctx.beginPath();
  ctx.moveTo(x, y);
  ctx.lineTo(x + Math.cos(a) * 24, y - Math.sin(a) * 24);
  ctx.stroke();
  ctx.beginPath();
  ctx.arc(x, y, 4, 0, 2 * Math.PI);
  ctx.fill();
}

/**
 * The obstacles used for planning (guide 5.9 Planning, ViewPlanObstEnabled: "red lines in the platform GUI"),
 * erratum E-GUI-005: the lines and circles GET_STATUS reports as observed (platform frame, E-MOT-003), which the
 * planner passes besides the map's own objects (E-MOT-006), drawn in red in the world frame. Returns the count.
 */
export function drawPlanObstacles(ctx: CanvasRenderingContext2D, cam: Camera, s: GetStatusReply, est: Pose): number {
  ctx.strokeStyle = "#d50000";
  ctx.lineWidth = 2;
  ctx.beginPath();
  for (const l of s.lines) {
    ctx.moveTo(...toScreen(cam, ...poseToWorld(est, l.sourceX, l.sourceY)));
    ctx.lineTo(...toScreen(cam, ...poseToWorld(est, l.targetX, l.targetY)));
  }
  for (const c of s.circles) {
    const [cx, cy] = toScreen(cam, ...poseToWorld(est, c.x, c.y));
    const r = Math.max(2, c.radius * cam.scale);
    ctx.moveTo(cx + r, cy);
    ctx.arc(cx, cy, r, 0, 2 * Math.PI);
  }
  ctx.stroke();
  return s.lines.length + s.circles.length;
}

/** The live data of one status telegram; returns how many scan points and ultrasonic readings it drew. */
export function drawStatus(
  ctx: CanvasRenderingContext2D,
  cam: Camera,
  s: GetStatusReply,
  fp: Footprint,
  us: UsSensor[],
  o: OverlayOptions,
): { scan: number; ultrasonic: number; path: number; planobst: number } {
  const est: Pose = { x: s.estX, y: s.estY, angle: s.estAngle / 1000 };
  const des: Pose = { x: s.cmdX, y: s.cmdY, angle: s.cmdAngle / 1000 };
  const out = { scan: 0, ultrasonic: 0, path: 0, planobst: 0 };
  if (o.path && s.path.length > 0) {
    ctx.strokeStyle = "#6a1b9a";
    ctx.lineWidth = 2;
    ctx.beginPath();
    s.path.forEach((p, i) => {
      const [sx, sy] = toScreen(cam, p.x, p.y);
      if (i === 0) {
        ctx.moveTo(sx, sy);
      } else {
        ctx.lineTo(sx, sy);
      }
    });
    ctx.stroke();
    out.path = s.path.length;
  }
  if (o.scan && s.scan.length > 0) {
    // guide 6.4 "Observed scan (platform coordinates)": x, y of each point in the platform frame
    ctx.fillStyle = "#e53935";
    for (const p of s.scan as unknown as Array<{ x: number; y: number }>) {
      const [sx, sy] = toScreen(cam, ...poseToWorld(est, p.x, p.y));
      ctx.fillRect(sx - 1, sy - 1, 2, 2);
    }
    out.scan = s.scan.length;
  }
  if (o.ultrasonic) {
    ctx.strokeStyle = "rgba(0,150,136,0.8)";
    ctx.lineWidth = 1;
    us.forEach((u, i) => {
      const d = s.usDistance[i] ?? 0;
      if (d <= 0) {
        return;
      }
      const a = (u.angle * Math.PI) / 180;
      const [sx, sy] = toScreen(cam, ...poseToWorld(est, u.x, u.y));
      const [ex, ey] = toScreen(cam, ...poseToWorld(est, u.x + Math.cos(a) * d, u.y + Math.sin(a) * d));
      ctx.beginPath();
      ctx.moveTo(sx, sy);
      ctx.lineTo(ex, ey);
      ctx.stroke();
      out.ultrasonic++;
    });
  }
  if (o.planObstacles) {
    // over the scan points, which lie on the observed lines
    out.planobst = drawPlanObstacles(ctx, cam, s, est);
  }
  if (o.localization && (s.covMajor > 0 || s.covMinor > 0)) {
    const [cx, cy] = toScreen(cam, est.x, est.y);
    ctx.strokeStyle = "rgba(255,143,0,0.9)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.ellipse(
      cx,
      cy,
      Math.max(2, s.covMajor * cam.scale),
      Math.max(2, s.covMinor * cam.scale),
      (-s.covAxisAngle / 1000) * (Math.PI / 180),
      0,
      2 * Math.PI,
    );
    ctx.stroke();
  }
  if (o.showDesired) {
    drawPlatform(ctx, cam, des, fp, "#43a047", true);
  }
  if (o.showEstimated) {
    drawPlatform(ctx, cam, est, fp, "#1565c0", false);
  }
  return out;
}
