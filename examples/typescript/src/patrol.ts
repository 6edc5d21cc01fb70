/**
 * examples/patrol.py in TypeScript, on the generated client (`pltf stubs --lang typescript`): patrol the stations
 * of the platform's roadmap in order, retrying a goal the platform refuses. Same options, output lines and exit
 * status as the Python patrol:
 *
 *   sh build.sh && node dist/patrol.js --target 127.0.0.1:10002 --stations Corridor_01,Kitchen,Corridor_02
 *
 * Lines: `reached NAME x=.. y=.. angle=..`, `refused NAME attempt I/N: why`, `skipped NAME`, `round R done`.
 * Exit 0: every station reached; 1: one skipped; 2: the platform cannot be used (unreachable, no such station).
 */

import {
  Client,
  CommandRejected,
  GetStatusReply,
  MotionMode,
  OperationState,
  WaitTimeout,
} from "./platformctrl";

interface Station {
  name: string;
  x: number; // mm
  y: number; // mm
  angleDeg: number; // roadmap angles are degrees (toolkit erratum E-XML-007)
}

interface Options {
  host: string;
  port: number;
  stations: string[];
  rounds: number;
  retries: number;
  retryDelayS: number;
  timeoutS: number;
  drive: "plan" | "roadmap";
}

class UsageError extends Error {}

function parseArgs(argv: string[]): Options {
  const o: Options = { host: "127.0.0.1", port: 10002, stations: [], rounds: 1, retries: 3, retryDelayS: 2,
    timeoutS: 180, drive: "plan" };
  for (let i = 0; i < argv.length; i += 2) {
    const [flag, value] = [argv[i], argv[i + 1]];
    if (value === undefined) throw new UsageError(`${flag} needs a value`);
    const number = (): number => {
      const n = Number(value);
      if (!Number.isFinite(n) || n < 0) throw new UsageError(`${flag}: expected a number >= 0, got ${value}`);
      return n;
    };
    if (flag === "--target") {
      const m = /^(.+):(\d+)$/.exec(value);
      if (m === null || Number(m[2]) < 1 || Number(m[2]) > 65535) throw new UsageError(`expected HOST:PORT, got ${value}`);
      [o.host, o.port] = [m[1].replace(/^\[|\]$/g, ""), Number(m[2])];
    } else if (flag === "--stations") o.stations = value.split(",");
    else if (flag === "--rounds") o.rounds = number();
    else if (flag === "--retries") o.retries = number();
    else if (flag === "--retry-delay") o.retryDelayS = number();
    else if (flag === "--timeout") o.timeoutS = number();
    else if (flag === "--drive" && (value === "plan" || value === "roadmap")) o.drive = value;
    else throw new UsageError(`unknown option ${flag} ${value}`);
  }
  return o;
}

/** The stations of a roadmap document (guide 6.5 Roadmap), by name: a small reader for this one element. */
function stationsOf(xml: string): Map<string, Station> {
  const out = new Map<string, Station>();
  const attr = (tag: string, name: string): string | undefined =>
    new RegExp(`\\s${name}\\s*=\\s*"([^"]*)"`).exec(tag)?.[1];
  for (const m of xml.matchAll(/<station\b([^>]*)>([\s\S]*?)<\/station>/g)) {
    const point = /<point\b[^>]*>/.exec(m[2]);
    if (point === null) continue;
    const name = attr(m[1], "name") ?? attr(m[1], "id") ?? "";
    out.set(name, { name, x: Math.trunc(Number(attr(point[0], "x") ?? 0)), y: Math.trunc(Number(attr(point[0], "y") ?? 0)),
      angleDeg: Number(attr(m[1], "angle") ?? 0) });
  }
  return out;
}

const sleep = (ms: number): Promise<void> => new Promise((resolve) => setTimeout(resolve, ms));

/** Bring the platform up and to state Running in mode Automatic (the mode only changes in Ready). */
async function runningInAutomatic(pltf: Client): Promise<void> {
  const state = (s: OperationState) => (t: GetStatusReply): boolean => t.operationState === s;
  let status = await pltf.getStatus();
  if (status.operationState === OperationState.ST_OP_NOT_INITIALIZED) {
    await pltf.connectToPltf();
    await pltf.initPltf();
    status = await pltf.waitUntil(state(OperationState.ST_OP_READY), 30000, 50, "state Ready");
  }
  if (status.motionMode !== MotionMode.MODE_MOTION_AUTOMATIC) {
    if (status.operationState !== OperationState.ST_OP_READY) {
      await pltf.stop();
      await pltf.waitUntil(state(OperationState.ST_OP_READY), 10000, 50, "state Ready");
    }
    await pltf.setMode(MotionMode.MODE_MOTION_AUTOMATIC);
    await pltf.waitUntil((t) => t.motionMode === MotionMode.MODE_MOTION_AUTOMATIC, 10000, 50, "mode Automatic");
  }
  if ((await pltf.getStatus()).operationState !== OperationState.ST_OP_RUNNING) {
    await pltf.start();
    await pltf.waitUntil(state(OperationState.ST_OP_RUNNING), 10000, 50, "state Running");
  }
}

async function visit(pltf: Client, st: Station, o: Options, tolerance: number): Promise<boolean> {
  const attempts = o.retries + 1;
  for (let attempt = 1; attempt <= attempts; attempt++) {
    let why: string;
    try {
      if (attempt > 1) await runningInAutomatic(pltf); // an emergency stop or another client may have stopped it
      if (o.drive === "roadmap") await pltf.moveToStation(st.name);
      else await pltf.moveAbs(st.x, st.y, Math.round(st.angleDeg * 1000));
      const s = await pltf.waitTargetReached(o.timeoutS * 1000);
      const off = Math.hypot(s.estX - st.x, s.estY - st.y);
      if (off <= tolerance) {
        console.log(`reached ${st.name} x=${s.estX} y=${s.estY} angle=${(s.estAngle / 1000).toFixed(1)}`);
        return true;
      }
      why = `stopped ${off.toFixed(0)} mm from the station`; // e.g. a MOVE_TO_STATION the platform ignored
    } catch (e) {
      if (!(e instanceof CommandRejected || e instanceof WaitTimeout)) throw e;
      why = e.message;
    }
    console.log(`refused ${st.name} attempt ${attempt}/${attempts}: ${why}`);
    if (attempt < attempts) await sleep(o.retryDelayS * 1000);
  }
  console.log(`skipped ${st.name}`);
  return false;
}

async function patrol(pltf: Client, o: Options): Promise<number> {
  const known = stationsOf((await pltf.getRoadmap()).xml);
  const names = o.stations.length > 0 ? o.stations : [...known.keys()];
  const missing = names.filter((n) => !known.has(n));
  if (missing.length > 0 || names.length === 0) {
    console.error(`patrol: error: no station ${missing.join(", ")} in the roadmap (it has: ${[...known.keys()].join(", ")})`);
    return 2;
  }
  // target reached means within TargetReachedTolPos of the goal (toolkit erratum E-PAR-021); allow it twice
  const tolerance = 2 * Number((await pltf.getPltfParam("TargetReachedTolPos")).value);
  await runningInAutomatic(pltf);
  let allReached = true;
  for (let round = 1; o.rounds === 0 || round <= o.rounds; round++) {
    for (const name of names) {
      allReached = (await visit(pltf, known.get(name) as Station, o, tolerance)) && allReached;
    }
    console.log(`round ${round} done`);
  }
  return allReached ? 0 : 1;
}

async function main(): Promise<number> {
  let o: Options;
  try {
    o = parseArgs(process.argv.slice(2));
  } catch (e) {
    console.error(`patrol: error: ${(e as Error).message}`);
    return 2;
  }
  let pltf: Client;
  try {
    pltf = await Client.connect(o.host, o.port, 10000);
  } catch (e) {
    console.error(`patrol: error: cannot connect to ${o.host}:${o.port}: ${(e as Error).message}`);
    return 2;
  }
  try {
    return await patrol(pltf, o);
  } catch (e) {
    console.error(`patrol: error: ${(e as Error).message}`);
    return 2;
  } finally {
    pltf.close();
  }
}

main().then((code) => {
  process.exitCode = code;
});
