// The document shell (issue 31) with an in-memory document: a list of words, one per line, a platform that
// stores what is sent (or refuses to take it), and dialogs that answer as scripted. What a user observes: the
// messages, the file downloaded, what the platform holds, whether the editor closed.
import { describe, expect, it } from "vitest";
import type { Action, EditHistory } from "../src/editor/history";
import type { Key } from "../src/i18n/i18n";
import {
  type Closing,
  type DocumentKind,
  DocumentShell,
  fileNameOf,
  type Replaced,
  type ShellEvent,
} from "../src/editor/shell";
import type { Verdict } from "../src/editor/validate";

/** A list of words with snapshot undo: the smallest EditHistory. */
class Words implements EditHistory {
  private done: Array<{ before: string[]; after: string[]; label: Action }> = [];
  private undone: Array<{ before: string[]; after: string[]; label: Action }> = [];
  private saved: object | null = null;
  constructor(public words: string[]) {}
  add(word: string): void {
    const after = [...this.words, word];
    this.done.push({ before: this.words, after, label: { key: "act.addObject" as Key, words: { kind: word } } });
    this.undone = [];
    this.words = after;
  }
  undo(): Action | null {
    const s = this.done.pop();
    if (s === undefined) return null;
    this.undone.push(s);
    this.words = s.before;
    return s.label;
  }
  redo(): Action | null {
    const s = this.undone.pop();
    if (s === undefined) return null;
    this.done.push(s);
    this.words = s.after;
    return s.label;
  }
  get canUndo(): boolean {
    return this.done.length > 0;
  }
  get canRedo(): boolean {
    return this.undone.length > 0;
  }
  get label(): Action | null {
    return this.done.at(-1)?.label ?? null;
  }
  markSaved(): void {
    this.saved = this.done.at(-1) ?? null;
  }
  get dirty(): boolean {
    return (this.done.at(-1) ?? null) !== this.saved;
  }
}

const WORDS: DocumentKind<Words> = {
  fallback: "words",
  ext: ".txt",
  parse: (text) => {
    if (!text.startsWith("words\n")) {
      throw new Error("not a list of words");
    }
    return new Words(text.split("\n").slice(1).filter(Boolean));
  },
  blank: () => new Words([]),
  serialise: (h) => {
    if (h.words.includes("unwritable")) {
      throw new Error("cannot write 'unwritable'");
    }
    return ["words", ...h.words].join("\n");
  },
  validate: async (text): Promise<Verdict> =>
    text.includes("bad")
      ? { ok: false, message: "'bad' is not allowed", line: text.split("\n").indexOf("bad") + 1 }
      : { ok: true },
  same: (a, b) => a === b,
  counts: (h) => ({ n: h.words.length }),
  text: (event: ShellEvent, words) => `${event}${words === undefined ? "" : ` ${JSON.stringify(words)}`}`,
  action: (said, action) => `${said}${action === null ? "" : ` ${action.words?.kind}`}`,
};

/** The shell over an in-memory platform and scripted dialogs, and what each side saw. */
function setup(platform = { text: "words\nalpha\nbeta", name: "plant" }) {
  const seen = {
    said: [] as string[],
    downloads: [] as Array<[string, string]>,
    replaced: [] as Replaced[],
    changed: 0,
    closed: 0,
    invalid: [] as Array<number | null>,
    asked: [] as boolean[],
    sent: [] as Array<[string, string]>,
  };
  const script = { closing: "saved" as Closing, fileName: null as string | null, takes: true, reachable: true };
  const shell: DocumentShell<Words> = new DocumentShell(
    WORDS,
    {
      fetch: async () => {
        if (!script.reachable) throw new Error("no reply: timeout");
        return { ...platform };
      },
      send: (name, text) => {
        if (!script.reachable) throw new Error("not connected");
        seen.sent.push([name, text]);
        if (script.takes) Object.assign(platform, { name, text });
      },
    },
    {
      say: (s) => seen.said.push(s),
      changed: () => seen.changed++,
      replaced: (how) => seen.replaced.push(how),
      invalid: (v) => seen.invalid.push(v.line),
      close: () => seen.closed++,
    },
    {
      download: (f, text) => seen.downloads.push([f, text]),
      askToClose: async (dirty) => {
        seen.asked.push(dirty);
        return dirty ? script.closing : "closed";
      },
      askFileName: async () => script.fileName,
    },
  );
  return { shell, seen, script, platform };
}

describe("the document shell: Undo and Redo (issue 35)", () => {
  it("say the action they took back or did again, or that there was none", async () => {
    const { shell, seen } = setup();
    await shell.load();
    shell.undo();
    expect(seen.said.at(-1)).toBe("nothingToUndo");
    shell.history.add("gamma");
    shell.undo();
    expect([seen.said.at(-1), shell.history.words]).toEqual(["undone gamma", ["alpha", "beta"]]);
    shell.redo();
    expect([seen.said.at(-1), shell.history.words]).toEqual(["redone gamma", ["alpha", "beta", "gamma"]]);
    shell.redo();
    expect(seen.said.at(-1)).toBe("nothingToRedo");
  });
});

describe("the document shell: file actions", () => {
  it("loads the platform's document under its name, or says why not and keeps its own", async () => {
    const { shell, seen, script } = setup();
    await shell.load();
    expect(shell.history.words).toEqual(["alpha", "beta"]);
    expect([shell.name, shell.fileName]).toEqual(["plant", "plant.txt"]);
    expect(seen.replaced).toEqual(["loaded"]);
    expect(seen.said.at(-1)).toBe('loaded {"n":2}');
    script.reachable = false;
    const before = shell.history;
    await shell.load();
    expect(seen.said.at(-1)).toBe("no reply: timeout");
    expect(shell.history).toBe(before);
  });

  it("opens a file under its name without the extension; refuses another kind with the reason", () => {
    const { shell, seen } = setup();
    shell.open("hall.v2.txt", "words\nx\ny\nz");
    expect([shell.name, shell.history.words.length, seen.said.at(-1)]).toEqual([
      "hall.v2",
      3,
      'opened {"file":"hall.v2.txt","n":3}',
    ]);
    const kept = shell.history;
    shell.open("office.map", "<map/>");
    expect(seen.said.at(-1)).toBe('openFailed {"file":"office.map","why":"not a list of words"}');
    expect([shell.history, shell.name, seen.replaced]).toEqual([kept, "hall.v2", ["opened"]]);
  });

  it("saves a download named after the document (the fallback when it has none); clean after", () => {
    const { shell, seen } = setup();
    shell.history.add("one");
    expect(shell.history.dirty).toBe(true);
    shell.save();
    expect(seen.downloads).toEqual([["words.txt", "words\none"]]);
    expect(shell.history.dirty).toBe(false);
    expect(seen.said.at(-1)).toBe('saved {"file":"words.txt"}');
  });

  it("saves as the name typed, with the extension, and keeps it as the document's name; cancel saves nothing", async () => {
    const { shell, seen, script } = setup();
    script.fileName = "night/shift";
    await shell.saveAs();
    expect(seen.downloads).toEqual([["night_shift.txt", "words"]]);
    expect([shell.name, shell.fileName]).toEqual(["night_shift", "night_shift.txt"]);
    script.fileName = null;
    await shell.saveAs();
    expect(seen.downloads.length).toBe(1);
  });

  it("starts a blank document at New", async () => {
    const { shell, seen } = setup();
    await shell.load();
    shell.newDocument();
    expect([shell.history.words, shell.name, seen.replaced]).toEqual([[], "", ["loaded", "new"]]);
  });

  it("undoes and redoes the document's history and shows it each time", () => {
    const { shell, seen } = setup();
    shell.history.add("a");
    const n = seen.changed;
    shell.undo();
    expect(shell.history.words).toEqual([]);
    shell.redo();
    expect(shell.history.words).toEqual(["a"]);
    expect(seen.changed).toBe(n + 2);
  });
});

describe("the document shell: send then verify", () => {
  it("sends, marks the document clean, and reads it back: active", async () => {
    const { shell, seen, platform } = setup();
    shell.history.add("gamma");
    expect(await shell.send()).toBe(true);
    expect(seen.sent).toEqual([["edited", "words\ngamma"]]);
    expect(platform.text).toBe("words\ngamma");
    expect(shell.history.dirty).toBe(false);
    expect(seen.said.slice(-2)).toEqual(['sent {"n":1}', 'active {"n":1}']);
  });

  it("says when the platform did not take the document", async () => {
    const { shell, seen, script } = setup();
    await shell.load();
    script.takes = false;
    shell.history.add("delta");
    await shell.send();
    expect(seen.sent).toEqual([["plant", "words\nalpha\nbeta\ndelta"]]);
    expect(seen.said.at(-1)).toBe('notTaken {"n":3}');
  });

  it("does not send an invalid document: the reason said and the line handed to the panel", async () => {
    const { shell, seen } = setup();
    shell.history.add("ok");
    shell.history.add("bad");
    expect(await shell.send()).toBe(false); // a fleet's editor keeps the document's owner (E-GUI-012)
    expect(seen.sent).toEqual([]);
    expect(seen.invalid).toEqual([3]);
    expect(seen.said.at(-1)).toBe(`invalid {"why":"'bad' is not allowed"}`);
    expect(shell.history.dirty).toBe(true);
  });

  it("says why a document cannot be written or sent, and it stays dirty", async () => {
    const { shell, seen, script } = setup();
    shell.history.add("unwritable");
    expect(await shell.send()).toBe(false);
    expect(seen.said.at(-1)).toBe("cannot write 'unwritable'");
    shell.history.undo();
    shell.history.add("fine");
    script.reachable = false;
    expect(await shell.send()).toBe(false);
    expect(seen.said.at(-1)).toBe("not connected");
    expect([seen.sent, shell.history.dirty]).toEqual([[], true]);
  });
});

describe("the document shell: close with changes", () => {
  it("closes at once without changes", async () => {
    const { shell, seen } = setup();
    expect(await shell.close()).toBe("closed");
    expect([seen.asked, seen.closed, seen.said.at(-1)]).toEqual([[false], 1, "closed"]);
  });

  it("asks with changes: Save downloads and closes", async () => {
    const { shell, seen } = setup();
    shell.history.add("keep");
    expect(await shell.close()).toBe("saved");
    expect([seen.asked, seen.downloads, seen.closed]).toEqual([[true], [["words.txt", "words\nkeep"]], 1]);
  });

  it("asks with changes: Close without saving drops them; Cancel keeps the editor open with them", async () => {
    const { shell, seen, script } = setup();
    shell.history.add("drop");
    script.closing = "cancelled";
    expect(await shell.close()).toBe("cancelled");
    expect([seen.closed, shell.history.words]).toEqual([0, ["drop"]]);
    script.closing = "discarded";
    expect(await shell.close()).toBe("discarded");
    expect([seen.closed, shell.history.words, seen.downloads]).toEqual([1, [], []]);
  });
});

describe("file names", () => {
  it("replace what a file system refuses, add the extension once, fall back when empty", () => {
    expect(fileNameOf('a:b*c?"d', "map", ".map")).toBe("a_b_c_d.map");
    expect(fileNameOf("office.map", "map", ".map")).toBe("office.map");
    expect(fileNameOf("  ", "roadmap", ".rm")).toBe("roadmap.rm");
  });
});
