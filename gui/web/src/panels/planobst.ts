/**
 * The planning obstacles switch (guide 5.9 Planning: ViewPlanObstEnabled "View the obstacles used for planning
 * (red lines in the platform GUI)"). The switch is the platform's parameter, not a local option (erratum
 * E-GUI-005): the map view draws the obstacles while the platform says ViewPlanObstEnabled is true. The GUI learns
 * the value from every GET_PLTF_PARAM_VEC and GET_PLTF_PARAM reply it sees (on connecting, in the parameters
 * window); the checkbox in View Options sets it with CMD_SET_PLTF_PARAM and reads it back.
 */
import { h } from "../dom";
import { bind } from "../i18n/i18n";
import { GetPltfParamReply, GetPltfParamRequest, GetPltfParamVecReply, SetPltfParamRequest } from "../pltf";
import type { PlatformSession } from "../session/session";
import { commands } from "./control";
import type { ViewOptions } from "./viewoptions";

export const PLAN_OBST_PARAM = "ViewPlanObstEnabled";

/** The parameter's text as the platform sends it (erratum E-PAR-005: true/false/1/0). */
export function paramTrue(value: string): boolean {
  const v = value.trim().toLowerCase();
  return v === "true" || v === "1";
}

export function planObstacleSwitch(
  session: PlatformSession,
  options: ViewOptions,
  say: (s: string) => void,
): HTMLElement {
  const input = h("input", { type: "checkbox" });
  const caption = h("span");
  bind(caption, "opt.planObstacles", { name: false });
  bind(input, "opt.planObstacles", { text: false });
  const learn = (value: string) => {
    options.planObstacles = paramTrue(value);
    input.checked = options.planObstacles;
    options.changed.publish();
  };
  session.replies.subscribe((r) => {
    if (r instanceof GetPltfParamReply && r.key === PLAN_OBST_PARAM) {
      learn(r.value);
    } else if (r instanceof GetPltfParamVecReply) {
      const e = r.parameters.find((p) => p.key === PLAN_OBST_PARAM);
      if (e !== undefined) {
        learn(e.value);
      }
    }
  });
  input.addEventListener("change", () => {
    try {
      session.send(new SetPltfParamRequest({ key: PLAN_OBST_PARAM, value: String(input.checked) }));
    } catch (e) {
      input.checked = options.planObstacles;
      say((e as Error).message);
      return;
    }
    session.request(new GetPltfParamRequest({ key: PLAN_OBST_PARAM })).catch((e: Error) => say(e.message));
  });
  // the switch sets the platform's parameter: a command (issue 33)
  return commands(session, h("label", { class: "check" }, input, caption));
}
