/** A named stream of values with the last one kept: what panels subscribe to (Foxglove's "topics"). */
export class Topic<T> {
  private listeners = new Set<(value: T) => void>();
  last: T | undefined;

  subscribe(fn: (value: T) => void, replay = true): () => void {
    this.listeners.add(fn);
    if (replay && this.last !== undefined) {
      fn(this.last);
    }
    return () => this.listeners.delete(fn);
  }

  publish(value: T): void {
    this.last = value;
    for (const fn of this.listeners) {
      try {
        fn(value);
      } catch (e) {
        console.warn("a panel failed on an update:", e);
      }
    }
  }
}
