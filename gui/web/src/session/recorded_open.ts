/**
 * Which recording the page shows (pltf gui --session FILE): the gateway's GET /api/recording says whether it is a
 * session file it has indexed (GatewaySource) or an MCAP file the page reads itself (McapSource).
 */
import {
  GatewaySource,
  type RecordedEvent,
  type RecordedFrame,
  RecordedSession,
  type RecordingInfo,
  type RecordingSource,
} from "./recorded";
import { McapSource } from "./recorded_mcap";

export class GatewayOrMcap implements RecordingSource {
  private inner: RecordingSource | null = null;
  onEvents?: (events: RecordedEvent[], complete: boolean) => void;
  constructor(readonly base: string) {}

  async info(): Promise<RecordingInfo> {
    if (this.inner === null) {
      const gateway = new GatewaySource(this.base);
      const info = (await gateway.info()) as RecordingInfo & { url?: string };
      const url = new URL(info.url ?? "recording.mcap", window.location.href).href;
      this.inner = info.kind === "mcap" ? new McapSource(url, info.file) : gateway;
      this.inner.onEvents = (events, complete) => this.onEvents?.(events, complete);
    }
    return this.inner.info();
  }

  at(t: number, since: number, limit: number) {
    return this.inner?.at(t, since, limit) ?? Promise.resolve({ state: [], wire: [] });
  }

  history(t: number, span: number, points: number): Promise<RecordedFrame[]> {
    return this.inner?.history(t, span, points) ?? Promise.resolve([]);
  }
}

/** The page's session for ?recording=FILE: the gateway's recording, whichever kind. */
export function recordedSession(): RecordedSession {
  return new RecordedSession(new GatewayOrMcap(new URL("api/recording", window.location.href).href));
}
