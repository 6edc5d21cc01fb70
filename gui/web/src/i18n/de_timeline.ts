/** German labels of the recorded-session timeline (pltf gui --session, issue 35). */
import type { enTimeline } from "./en_timeline";

export const deTimeline: Record<keyof typeof enTimeline, string> = {};
