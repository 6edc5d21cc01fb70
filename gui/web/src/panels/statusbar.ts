/**
 * The status bar (guide 5.6, 6.4 CMD_GET_STATUS): system state, emergency state, motion mode, planner state,
 * battery, localization, collision, the estimated and the desired pose, and the connection in words.
 * Values are in the guide's units as plain numbers: mm, degrees, volts.
 */
import { h, readout, setText } from "../dom";
import { type Key, onLanguage, t } from "../i18n/i18n";
import { EmergencyState, Flag, type GetStatusReply } from "../pltf";
import type { ConnEvent, PlatformSession } from "../session/session";
import { connText } from "../session/connwords";

export function poseText(x: number, y: number, angleMilliDeg: number): string {
  return `x ${x} mm, y ${y} mm, ${(angleMilliDeg / 1000).toFixed(1)}°`;
}

export function statusBar(session: PlatformSession): HTMLElement {
  const conn = readout("status.connection", "connection");
  const items = {
    system: readout("status.system"),
    emergency: readout("status.emergency"),
    mode: readout("status.motionMode"),
    planner: readout("status.planner"),
    battery: readout("status.battery"),
    localization: readout("status.localization"),
    collision: readout("status.collision"),
    est: readout("status.estimated", "pose"),
    des: readout("status.desired", "pose"),
  };
  const root = h("footer", { class: "status-bar" }, conn.root, ...Object.values(items).map((i) => i.root));
  let last: GetStatusReply | null = null;
  let lastConn: ConnEvent | null = null;
  const show = () => {
    const ev = lastConn;
    setText(conn.value, ev === null ? t("conn.closed") : connText(ev));
    conn.value.dataset.event = ev?.event ?? "closed";
    const s = session.connected ? last : null;
    if (s === null) {
      for (const i of Object.values(items)) {
        setText(i.value, "-");
        i.value.removeAttribute("data-value");
      }
      return;
    }
    const set = (o: { value: HTMLOutputElement }, text: string, value: string | number) => {
      setText(o.value, text);
      o.value.dataset.value = String(value);
    };
    set(items.system, t(`opstate.${s.operationState}` as Key), s.operationState);
    set(items.emergency, t(`emstate.${s.emergencyState}` as Key), s.emergencyState);
    items.emergency.root.classList.toggle("alarm", s.emergencyState === EmergencyState.ST_EM_ACTIVE);
    set(items.mode, t(`mode.${s.motionMode}` as Key), s.motionMode);
    set(items.planner, t(`planner.${s.plannerState}` as Key), s.plannerState);
    // erratum E-REP-006: the battery voltage is sent in mV; shown in volts
    set(items.battery, `${(s.ioBatteryVoltage / 1000).toFixed(2)} V`, s.ioBatteryVoltage / 1000);
    const loc = s.localizationLost === Flag.ON ? t("status.lost") : t("status.ok");
    set(items.localization, s.lookupPercent > 0 ? `${loc} (${s.lookupPercent} %)` : loc, s.localizationLost);
    items.localization.root.classList.toggle("alarm", s.localizationLost === Flag.ON);
    set(items.collision, s.collision === Flag.ON ? t("status.yes") : t("status.no"), s.collision);
    items.collision.root.classList.toggle("alarm", s.collision === Flag.ON);
    set(items.est, poseText(s.estX, s.estY, s.estAngle), `${s.estX},${s.estY},${s.estAngle / 1000}`);
    set(items.des, poseText(s.cmdX, s.cmdY, s.cmdAngle), `${s.cmdX},${s.cmdY},${s.cmdAngle / 1000}`);
  };
  session.status.subscribe((s) => {
    last = s;
    show();
  });
  session.conn.subscribe((ev) => {
    lastConn = ev;
    show();
  });
  onLanguage(show);
  return root;
}
