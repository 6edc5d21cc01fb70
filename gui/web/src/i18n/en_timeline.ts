/** English labels of the recorded-session timeline (pltf gui --session, issue 35). */
export const enTimeline = {
  "timeline.caption": "Timeline",
  "timeline.play": "Play",
  "timeline.pause": "Pause",
  "timeline.speed": "Speed",
  "timeline.scrubber": "Time in the recording",
  "timeline.events": "Commands the application sent",
  "timeline.mark": "{name} at {at}",
  "timeline.readOnly": "A recording is shown: nothing is sent to any platform.",
  "timeline.notSent": "not sent: a recording is shown",
  "timeline.conn": "recording {file}",
  "timeline.noStatus": "recording {file}: no status reply yet at this time",
  "timeline.failed": "The recording cannot be read: {detail}",
} as const;
