/** The spec data that is not in the generated client: parameters, enum descriptions, answered telegrams. */
import data from "./generated/spec.json";

export type ParamType = "BOOLEAN" | "INTEGER" | "DOUBLE";

export interface ParamDef {
  name: string;
  category: string;
  type: ParamType;
  default: boolean | number;
  unit: string | null;
  min: number;
  max: number;
  description: string;
  writable: boolean;
}

export const PARAMETERS: readonly ParamDef[] = data.parameters as ParamDef[];
export const PARAM_BY_NAME: ReadonlyMap<string, ParamDef> = new Map(PARAMETERS.map((p) => [p.name, p]));
/** guide 6.1: the identifiers whose requests are answered. */
export const ANSWERED: ReadonlySet<number> = new Set(Object.values(data.answered as Record<string, number>));
export const ENUMS = data.enums as Record<string, { description: string; values: Record<string, number> }>;

/** guide 5.9 figure 9: the tabs of the parameters window, in the window's order, with their categories. */
export const PARAM_TABS: ReadonlyArray<[string, string]> = [
  ["SURVEILLANCE", "Surveillance"],
  ["TRACKING_DETECTION", "Tracking & Detection"],
  ["USONIC", "UltraSonic"],
  ["MAPPING", "Mapping"],
  ["MOTION_CTRL", "Motion Control"],
  ["PLANNING", "Planning"],
  ["COLLISION", "Collision"],
  ["GEOM", "Geometry"],
  ["INFRARED", "InfraRed"],
  ["IPO", "Interpolation"],
  ["LOCALIZATION", "Localization"],
];
