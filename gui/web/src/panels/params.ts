/**
 * Platform parameters (guide 5.9, figure 9): the guide's categories as tabs, the parameters of the selected tab
 * with their values (CMD_GET_PLTF_PARAM_VEC), a text field and Set (CMD_SET_PLTF_PARAM), then a read-back
 * (CMD_GET_PLTF_PARAM) whose answer is shown. Values are type- and range-checked from spec/parameters.yaml before
 * anything is sent; a parameter the spec does not know is checked against the platform's own type and bounds.
 */
import { h } from "../dom";
import { bind, onLanguage, t } from "../i18n/i18n";
import { checkParam } from "../params_check";
import {
  GetPltfParamReply,
  GetPltfParamRequest,
  type GetPltfParamVecReply,
  GetPltfParamVecRequest,
  ParamCategory,
  type ParamEntry,
  SetPltfParamRequest,
} from "../pltf";
import { PARAM_BY_NAME, PARAM_TABS, type ParamDef } from "../spec";
import type { PlatformSession } from "../session/session";
import { commands } from "./control";

const TYPES = ["BOOLEAN", "INTEGER", "DOUBLE"] as const;

function definition(e: ParamEntry): ParamDef {
  return (
    PARAM_BY_NAME.get(e.key) ?? {
      name: e.key,
      category: ParamCategory[e.category],
      type: TYPES[e.dataType],
      default: 0,
      unit: null,
      min: e.minimum,
      max: e.maximum,
      description: "",
      writable: true,
    }
  );
}

export function parametersWindow(session: PlatformSession): { root: HTMLElement; onShow: (on: boolean) => void } {
  let entries: ParamEntry[] = [];
  let tab = "IPO";
  let selected: string | null = null;
  const list = h("div", { role: "tablist", class: "dock-tabs" });
  bind(list, "menu.platformParameters", { text: false });
  const body = h("tbody");
  const grid = h(
    "table",
    { role: "grid" },
    h("thead", {}, h("tr", {}, h("th", {}, "parameter"), h("th", {}, "value"), h("th", {}, "range"))),
    body,
  );
  bind(grid, "param.table", { text: false });
  const value = h("input", { type: "text", disabled: true });
  const valueCaption = h("span");
  const setBtn = h("button", { type: "button", disabled: true });
  bind(setBtn, "param.set");
  const refresh = h("button", { type: "button" });
  bind(refresh, "param.refresh");
  const answer = h("p", { role: "status", class: "param-answer" });
  bind(answer, "param.answer", { text: false });
  const description = h("p", { class: "hint" });

  const load = () => {
    session.request<GetPltfParamVecReply>(new GetPltfParamVecRequest()).then(
      (r) => {
        entries = r.parameters;
        render();
      },
      (e: Error) => (answer.textContent = e.message),
    );
  };
  refresh.addEventListener("click", load);
  const renderTabs = () => {
    list.replaceChildren(
      ...PARAM_TABS.map(([cat, label]) => {
        const b = h("button", { type: "button", role: "tab", "aria-selected": String(cat === tab) }, label);
        b.addEventListener("click", () => {
          tab = cat;
          renderTabs();
          render();
        });
        return b;
      }),
    );
  };
  const select = (key: string) => {
    selected = key;
    const e = entries.find((x) => x.key === key);
    const def = e ? definition(e) : PARAM_BY_NAME.get(key);
    value.disabled = false;
    setBtn.disabled = false;
    value.value = e?.value ?? "";
    value.setAttribute("aria-label", `${t("param.value")} ${key}`);
    valueCaption.textContent = `${key}:`;
    description.textContent = def ? `${def.description}${def.writable ? "" : ` (${t("param.readOnly")})`}` : "";
    for (const row of body.querySelectorAll("tr")) {
      row.setAttribute("aria-selected", String(row.dataset.key === key));
    }
  };
  const render = () => {
    const shown = entries.filter((e) => ParamCategory[e.category] === tab);
    body.replaceChildren(
      ...shown.map((e) => {
        const def = definition(e);
        const range =
          def.type === "BOOLEAN" ? "true / false" : `${def.min} .. ${def.max}${def.unit ? ` ${def.unit}` : ""}`;
        const row = h(
          "tr",
          { tabindex: "0", "data-key": e.key, "aria-selected": String(e.key === selected) },
          h("td", {}, e.key),
          h("td", { class: "value" }, e.value),
          h("td", {}, range),
        );
        row.addEventListener("click", () => select(e.key));
        row.addEventListener("keydown", (ev) => ev.key === "Enter" && select(e.key));
        return row;
      }),
    );
  };
  const set = () => {
    const key = selected;
    const e = entries.find((x) => x.key === key);
    if (key === null || e === undefined) {
      return;
    }
    const checked = checkParam(definition(e), value.value);
    if (!checked.ok) {
      answer.textContent = `${t("param.refused")}: ${checked.reason}`;
      answer.dataset.outcome = "refused";
      return;
    }
    try {
      session.send(new SetPltfParamRequest({ key, value: checked.text }));
    } catch (err) {
      answer.textContent = (err as Error).message;
      return;
    }
    session.request<GetPltfParamReply>(new GetPltfParamRequest({ key })).then(
      (r) => {
        e.value = r.value;
        render();
        const ok = r.value === checked.text || Number(r.value) === Number(checked.text);
        answer.textContent = t(ok ? "param.accepted" : "param.notTaken", { key, sent: checked.text, value: r.value });
        answer.dataset.outcome = ok ? "accepted" : "not-taken";
      },
      (err: Error) => (answer.textContent = err.message),
    );
  };
  setBtn.addEventListener("click", set);
  value.addEventListener("keydown", (e) => e.key === "Enter" && set());
  session.params.subscribe((r) => {
    entries = r.parameters;
    render();
  });
  onLanguage(() => {
    renderTabs();
    if (selected) {
      value.setAttribute("aria-label", `${t("param.value")} ${selected}`);
    } else {
      value.setAttribute("aria-label", t("param.value"));
      valueCaption.textContent = `${t("param.value")}:`; // issue 35: a caption before a parameter is picked
    }
  });
  const root = h(
    "div",
    { class: "params" },
    list,
    h("div", { class: "row" }, refresh),
    grid,
    description,
    h("div", { class: "row" }, commands(session, h("label", { class: "field" }, valueCaption, value), setBtn)),
    answer,
  );
  return { root, onShow: (on) => on && session.connected && load() };
}

export { GetPltfParamReply };
