/**
 * Who drives (issue 33, gui/control.py): one tab at a time holds control of a target; the others watch.
 *
 * - `controlPanel`: says who drives ("you drive", "tab 2 (192.168.0.7) drives; you watch", "read-only") and offers
 *   "Take control", the one explicit way to take over (absent in a read-only GUI).
 * - `commands`: wraps controls that send commands (telegrams without a reply, guide 6.1) in a fieldset that is
 *   disabled while this tab may not command. A disabled fieldset disables every control in it whatever the
 *   control's own state, so the panels keep enabling their buttons by the state chart as before. The gateway
 *   refuses such a tab's commands anyway; this only keeps the page honest about it.
 */
import { button, h, readout, setText } from "../dom";
import { onLanguage, t } from "../i18n/i18n";
import type { PlatformSession } from "../session/session";

export function commands(session: PlatformSession, ...children: Array<Node | string>): HTMLFieldSetElement {
  const group = h("fieldset", { class: "commands" }, ...children);
  const update = () => (group.disabled = !session.mayCommand);
  session.driving.subscribe(update);
  update();
  return group;
}

/** Put `el`, already in the page, into a `commands` group where it stands. */
export function guard<E extends HTMLElement>(session: PlatformSession, el: E): E {
  const group = commands(session);
  el.replaceWith(group);
  group.append(el);
  return el;
}

export function controlPanel(session: PlatformSession): HTMLElement {
  const said = readout("control.caption", "control");
  const take = button("control.take", () => session.takeControl(), { class: "take-control" });
  const root = h("div", { class: "control-bar" }, said.root, take);
  const show = () => {
    const d = session.drive;
    if (d === null) {
      setText(said.value, "-");
    } else if (d.read_only) {
      setText(said.value, t("control.readOnly"));
    } else if (d.holder === null) {
      setText(said.value, t("control.nobody"));
    } else {
      setText(said.value, d.you ? t("control.you") : t("control.other", { holder: d.holder }));
    }
    said.value.dataset.you = String(d?.you ?? false);
    take.hidden = d?.read_only ?? false;
    take.disabled = d === null || d.read_only || d.you;
  };
  session.driving.subscribe(show);
  onLanguage(show);
  return root;
}
