/**
 * The connection events in the reader's language. The gateway (gui/link.py) sends each event with an English
 * `message` and its parts as fields (detail, timeout, attempt, delay; a retry repeats its failure's `reason` and
 * fields); the text shown is built from the catalog and those fields, so it follows the language switch. The
 * `detail` stays in the words of the system or the codec that produced it. An event the catalog does not know
 * is shown with the gateway's own message.
 */
import { type Key, t } from "../i18n/i18n";
import type { ConnEvent } from "./session";

type Vars = Record<string, string | number>;

function vars(ev: ConnEvent): Vars {
  const out: Vars = { target: ev.target };
  for (const k of ["detail", "timeout", "attempt", "delay", "holder", "telegram"]) {
    const v = ev[k];
    if (typeof v === "string" || typeof v === "number") {
      out[k] = v;
    }
  }
  return out;
}

/** The catalog key of one event (its variant chosen by the fields it has), or null when there is none. */
function key(event: string, ev: ConnEvent): Key | null {
  const variants: Record<string, Key> = {
    connecting: "conn.ev.connecting",
    connected: "conn.ev.connected",
    refused: "conn.ev.refused",
    unreachable: ev.timeout !== undefined ? "conn.ev.unreachableTimeout" : "conn.ev.unreachable",
    turned_away: "conn.ev.turnedAway",
    dropped: ev.detail !== undefined ? "conn.ev.dropped" : "conn.ev.droppedClosed",
    timeout: "conn.ev.timeout",
    malformed: "conn.ev.malformed",
    gateway_lost: "conn.ev.gatewayLost",
    not_sent: "conn.ev.notSent",
    target_refused: "conn.ev.targetRefused",
    refused_command: ev.reason === "read_only" ? "conn.ev.refusedReadOnly" : "conn.ev.refusedViewer",
    closed:
      ev.by === "viewer" ? "conn.ev.closedByViewer" : ev.by === "gateway" ? "conn.ev.gatewayStopped" : "conn.ev.closed",
  };
  return variants[event] ?? null;
}

export function connText(ev: ConnEvent): string {
  if (ev.event === "retry") {
    const reason = typeof ev.reason === "string" ? ev.reason : "";
    const k = key(reason, ev);
    const failure = k === null ? t("conn.ev.lost") : t(k, vars(ev));
    return t("conn.ev.retry", { failure, delay: String(ev.delay ?? "") });
  }
  const k = key(ev.event, ev);
  return k === null ? ev.message : t(k, vars(ev));
}
