/** English labels of the keyboard help overlay and the toolbar tooltips (issue 35). */
export const enHelp = {} as const;
