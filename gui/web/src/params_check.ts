/**
 * Type and range check of a parameter value before it is sent (CMD_SET_PLTF_PARAM), from spec/parameters.yaml.
 * The value texts are the reference's (errata E-PAR-005, E-PAR-006): true/false/1/0, decimal integers, decimal
 * numbers with '.'. Returns the canonical text to send, or the reason it is refused.
 */
import type { ParamDef } from "./spec";

const INT = /^[+-]?[0-9]+$/;
const DOUBLE = /^[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$/;
const BOOL: Record<string, string> = { true: "true", "1": "true", false: "false", "0": "false" };

export type Checked = { ok: true; text: string } | { ok: false; reason: string };

export function checkParam(p: ParamDef, raw: string): Checked {
  const text = raw.trim();
  if (!p.writable) {
    return { ok: false, reason: `${p.name} is read-only (set in the parameter file at start-up)` };
  }
  if (p.type === "BOOLEAN") {
    const v = BOOL[text.toLowerCase()];
    return v === undefined ? { ok: false, reason: `${p.name}: expected true or false` } : { ok: true, text: v };
  }
  const pattern = p.type === "INTEGER" ? INT : DOUBLE;
  if (!pattern.test(text)) {
    const what = p.type === "INTEGER" ? "a whole number" : "a number with '.' as decimal point";
    return { ok: false, reason: `${p.name}: expected ${what}` };
  }
  const value = Number(text);
  if (!Number.isFinite(value) || value < p.min || value > p.max) {
    return { ok: false, reason: `${p.name}: ${text} is outside ${p.min} .. ${p.max}${p.unit ? ` ${p.unit}` : ""}` };
  }
  return { ok: true, text: p.type === "INTEGER" ? String(value) : text };
}
