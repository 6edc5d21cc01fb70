/**
 * The fleet's status lines (issue 30): one line per platform (name, operation state, motion mode, position,
 * connected or lost), its colour on the map; a click on a line (or on the platform's body on the map) selects it.
 *
 * Rules (session/fleet.ts): every platform is watched by a session of its own (no documents, no command) that
 * polls GET_STATUS while the platform is not selected and reads its parameters once per connection (its
 * footprint); the selected one is the target of the page's one commanding session, the one every other panel
 * holds, switched with `PlatformSession.open(target)`: motion, operation, menus and editors act on it alone, and
 * its status line and body read that session's GET_STATUS (one stream per platform on the wire). The selection is
 * kept in the address (`?selected=`) over a reload.
 */
import { h } from "../dom";
import { bind, type Key, onLanguage, t } from "../i18n/i18n";
import { type GetPltfParamVecReply, GetPltfParamVecRequest, type GetStatusReply } from "../pltf";
import {
  DocumentOwner,
  type FleetBody,
  type FleetMember,
  fleetMembers,
  type StatusLine,
  selectedHref,
  statusLine,
} from "../session/fleet";
import { PlatformSession } from "../session/session";
import type { Footprint } from "../view/overlay";
import { platformGeometry } from "./map/platform";
import type { MapView } from "./mapview";
import { dialog } from "../ui/dialog";
import { poseText } from "./statusbar";

/** GET_STATUS of a watched platform, Hz: the map's other bodies need no more (the selected one: 20 Hz) */
const WATCH_HZ = 5;

interface Watched {
  member: FleetMember;
  session: PlatformSession;
  status: GetStatusReply | null;
  /** its own outline (its GET_PLTF_PARAM_VEC), null until read */
  footprint: Footprint | null;
  everConnected: boolean;
  line: HTMLButtonElement;
  /** the words its line shows now, joined */
  said: string;
}

export interface Fleet {
  readonly root: HTMLElement;
  readonly selected: string;
  select(target: string): void;
  /** The platform's name (the fleet file's, else its address). */
  nameOf(target: string): string;
  /** Called after every switch of the selected platform. */
  onSwitch(f: () => void): void;
}

export function fleetPanel(
  wsUrl: string,
  targets: string[],
  selected: string,
  session: PlatformSession,
  map: MapView,
  onSelect: (target: string) => void,
): Fleet {
  const list = h("ul", { class: "fleet-lines" });
  const root = h("section", { class: "fleet" }, list);
  bind(root, "fleet.title", { text: false });
  bind(list, "fleet.title", { text: false });
  let current = selected;
  const switched: Array<() => void> = [];
  const watched: Watched[] = fleetMembers(targets).map((member) => {
    const line = h("button", { class: "fleet-line", type: "button", "data-target": member.target });
    line.style.borderLeftColor = member.colour;
    list.append(h("li", {}, line));
    const w: Watched = {
      member,
      session: new PlatformSession(wsUrl, member.target),
      status: null,
      footprint: null,
      everConnected: false,
      line,
      said: "",
    };
    w.session.fetchDocuments = false;
    w.session.setPolling("status", member.target !== current, WATCH_HZ);
    w.session.status.subscribe((s) => {
      if (w.member.target !== current) {
        seen(w, s);
      }
    });
    w.session.params.subscribe((r) => ownGeometry(w, r));
    w.session.conn.subscribe((ev) => {
      w.everConnected ||= ev.event === "connected";
      if (ev.event === "connected") {
        w.session.request(new GetPltfParamVecRequest()).catch(() => undefined); // its footprint, once a connection
      }
      show(w);
      drawn();
    });
    line.addEventListener("click", () => select(member.target));
    return w;
  });

  /** A status of `w`: from its watcher, or from the panels' session while it is selected. */
  function seen(w: Watched, s: GetStatusReply): void {
    w.status = s;
    show(w);
    drawn();
  }
  function ownGeometry(w: Watched, r: Pick<GetPltfParamVecReply, "parameters">): void {
    w.footprint = platformGeometry(r).footprint;
    drawn();
  }
  const selectedOne = (): Watched | undefined =>
    session.target === current ? watched.find((w) => w.member.target === current) : undefined;
  // the selected platform's one GET_STATUS stream is the panels' session's (and its parameters, when it reads them)
  session.status.subscribe((s) => {
    const w = selectedOne();
    if (w !== undefined) {
      seen(w, s);
    }
  });
  session.params.subscribe((r) => {
    const w = selectedOne();
    if (w !== undefined) {
      ownGeometry(w, r);
    }
  });

  const words = (l: StatusLine, w: Watched): string[] => {
    const conn = l.connected ? "fleet.connected" : w.everConnected ? "fleet.lost" : "fleet.waiting";
    if (l.pose === null) {
      return [l.name, t(conn)];
    }
    return [
      l.name,
      t(`opstate.${l.operationState}` as Key),
      t(`mode.${l.motionMode}` as Key),
      poseText(l.pose[0], l.pose[1], l.pose[2] * 1000),
      t(conn),
    ];
  };

  /** Is `w`'s status current: its watcher's connection, or the panels' session's while it is selected. */
  const live = (w: Watched): boolean =>
    w.member.target === current ? session.connected && session.target === current : w.session.connected;

  const show = (w: Watched) => {
    const up = live(w);
    const l = statusLine(w.member.name, up, up ? w.status : null);
    const said = words(l, w);
    if (said.join("\n") !== w.said) {
      // only when they change: the statuses (5-20 Hz) that say the same keep the words (and a press on one) as they are
      w.line.replaceChildren(...said.map((text, i) => h("span", { class: i === 0 ? "name" : "part" }, text)));
      w.said = said.join("\n");
    }
    w.line.setAttribute("aria-pressed", String(w.member.target === current));
    const d = w.line.dataset;
    d.name = w.member.name;
    d.connected = String(l.connected);
    d.operationState = l.operationState === null ? "" : String(l.operationState);
    d.motionMode = l.motionMode === null ? "" : String(l.motionMode);
    d.pose = l.pose === null ? "" : l.pose.join(",");
  };

  const drawn = () => {
    const bodies: FleetBody[] = watched.map((w) => {
      const st = live(w) ? w.status : null;
      return {
        name: w.member.name,
        target: w.member.target,
        colour: w.member.colour,
        selected: w.member.target === current,
        pose: st === null ? null : { x: st.estX, y: st.estY, angle: st.estAngle / 1000 },
        footprint: w.footprint,
      };
    });
    map.setFleet(bodies);
  };

  const select = (target: string) => {
    if (target === current || !targets.includes(target)) {
      return;
    }
    const before = watched.find((w) => w.member.target === current);
    const after = watched.find((w) => w.member.target === target);
    current = target;
    session.open(target); // the panels' session now talks to this platform alone
    // one GET_STATUS stream per platform: the one no longer selected is watched again, the selected one is not
    before?.session.setPolling("status", true, WATCH_HZ);
    after?.session.setPolling("status", false);
    if (after !== undefined) {
      after.status = null; // until the panels' session reads it (no stale pose from the watcher's last poll)
    }
    map.switched(); // nor the one before's pose in the map, drawn as the selected platform's
    history.replaceState(null, "", selectedHref(window.location.href, target));
    watched.forEach(show);
    drawn();
    onSelect(target);
    for (const f of switched) {
      f();
    }
  };

  map.onPick = select;
  void fleetNames(window.location.href).then((named) => {
    const names = new Map(named.map((n) => [n.target, n.name]));
    for (const w of watched) {
      w.member = { ...w.member, name: names.get(w.member.target) ?? w.member.name };
      show(w);
    }
    drawn();
    for (const f of switched) {
      f(); // the names came: the editors' headings say them
    }
  });
  onLanguage(() => watched.forEach(show));
  for (const w of watched) {
    show(w);
    w.session.open();
  }
  drawn();
  return {
    root,
    get selected() {
      return current;
    },
    select,
    nameOf: (target) => watched.find((w) => w.member.target === target)?.member.name ?? target,
    onSwitch: (f) => switched.push(f),
  };
}

/** What an editor needs of the fleet (erratum E-GUI-012): whose its document is, said and asked. */
export interface EditorFleet {
  /** the editor's heading: "Map of p00" ("p00's document; p01 is selected" after a switch) */
  readonly heading: HTMLElement;
  /** A new document came into the editor (loaded, opened, new): it is the selected platform's. */
  take(): void;
  /** Before Send: true to send; asks first when the document is another platform's than the selected one. */
  confirmSend(): Promise<boolean>;
  /** The selected platform got the document: it is that platform's now. */
  sent(): void;
}

/**
 * The fleet's side of an editor: a switch of the selected platform leaves the editor's document open, with its
 * history and unsaved changes; the heading names the platform it belongs to, and a Send to another platform asks.
 */
export function editorFleet(fleet: Fleet, kind: "map" | "roadmap"): EditorFleet {
  const owner = new DocumentOwner(() => fleet.selected);
  const heading = h("p", { class: "edit-owner", role: "note" });
  const words = () => ({ owner: fleet.nameOf(owner.platform), selected: fleet.nameOf(fleet.selected) });
  const said = () => {
    const w = words();
    heading.textContent = owner.elsewhere
      ? t("fleet.ownerElsewhere", w)
      : t(kind === "map" ? "fleet.mapOf" : "fleet.roadmapOf", w);
    heading.dataset.owner = w.owner;
    heading.dataset.selected = w.selected;
  };
  fleet.onSwitch(said);
  onLanguage(said);
  return {
    heading,
    take: () => {
      owner.take();
      said();
    },
    confirmSend: async () => {
      if (owner.elsewhere) {
        const ask = h("p", {}, t("fleet.sendAsk", words()));
        if ((await dialog("fleet.sendTitle", ask, ["edit.send", "dialog.cancel"])) !== 0) {
          return false;
        }
      }
      return true;
    },
    sent: () => {
      owner.take(); // sent to the selected platform: the document is its now (not before: a refused send keeps it)
      said();
    },
  };
}

/** Names from the gateway's fleet (`GET /api/targets`: the fleet file's); the addresses stay when it says none. */
export async function fleetNames(base: string): Promise<Array<{ name: string; target: string }>> {
  try {
    const r = await fetch(new URL("api/targets", base));
    const body = (await r.json()) as { fleet?: Array<{ name: string; target: string }> };
    return body.fleet ?? [];
  } catch {
    return [];
  }
}
