/** English labels of the recorded-session timeline (pltf gui --session, issue 35). */
export const enTimeline = {} as const;
