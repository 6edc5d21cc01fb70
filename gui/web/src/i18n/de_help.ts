/** German labels of the keyboard help overlay and the toolbar tooltips (issue 35). */
import type { enHelp } from "./en_help";

export const deHelp: Record<keyof typeof enHelp, string> = {};
