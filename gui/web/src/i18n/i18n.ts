/**
 * The message catalog (English, German) and the language switch. Unlike the original GUI (guide 5.7: "the GUI
 * must be restarted to apply the change") the labels change at once: every element takes its text and its
 * accessible name through `bind`, which re-applies them on a switch.
 */
import { de } from "./de";
import { en, type Key } from "./en";

export type Lang = "en" | "de";
export const CATALOGS: Record<Lang, Record<Key, string>> = { en, de };

let lang: Lang = (localStorage.getItem("pltf.lang") as Lang | null) ?? "en";
const appliers = new Set<() => void>();

export function language(): Lang {
  return lang;
}

export function t(key: Key, vars?: Record<string, string | number>): string {
  let s = CATALOGS[lang][key] ?? en[key] ?? key;
  if (vars) {
    for (const [k, v] of Object.entries(vars)) {
      s = s.replace(`{${k}}`, String(v));
    }
  }
  return s;
}

export function setLanguage(next: Lang): void {
  lang = next;
  localStorage.setItem("pltf.lang", next);
  document.documentElement.lang = next;
  for (const apply of appliers) {
    apply();
  }
}

/** Run `apply` now and after each language switch (it sets texts and names from `t`). */
export function onLanguage(apply: () => void): void {
  appliers.add(apply);
  apply();
}

/** An element whose text and accessible name are the catalog's `key` (`text: false`: name only, e.g. icons). */
export function bind<E extends HTMLElement>(
  el: E,
  key: Key,
  opts: { text?: boolean; name?: boolean; title?: Key } = {},
): E {
  onLanguage(() => {
    const s = t(key);
    if (opts.text !== false) {
      el.textContent = s;
    }
    if (opts.name !== false) {
      el.setAttribute("aria-label", s);
    }
    if (opts.title) {
      el.title = t(opts.title);
    }
  });
  return el;
}

export type { Key };
