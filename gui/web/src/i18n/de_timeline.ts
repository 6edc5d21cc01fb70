/** German labels of the recorded-session timeline (pltf gui --session, issue 35). */
import type { enTimeline } from "./en_timeline";

export const deTimeline: Record<keyof typeof enTimeline, string> = {
  "timeline.caption": "Zeitleiste",
  "timeline.play": "Abspielen",
  "timeline.pause": "Anhalten",
  "timeline.speed": "Geschwindigkeit",
  "timeline.scrubber": "Zeit in der Aufzeichnung",
  "timeline.events": "Befehle der Anwendung",
  "timeline.mark": "{name} bei {at}",
  "timeline.readOnly": "Eine Aufzeichnung wird gezeigt: nichts wird an eine Plattform gesendet.",
  "timeline.notSent": "nicht gesendet: eine Aufzeichnung wird gezeigt",
  "timeline.conn": "Aufzeichnung {file}",
  "timeline.noStatus": "Aufzeichnung {file}: zu dieser Zeit noch keine Statusantwort",
  "timeline.failed": "Die Aufzeichnung kann nicht gelesen werden: {detail}",
} as const;
