/**
 * A small XML reader and writer for the editors' documents (map, roadmap: guide 6.5), pure TypeScript with no
 * DOM, so the documents' round trip is the same in the browser and in the unit tests. It keeps elements,
 * attributes in their order, text and comments; it refuses a DOCTYPE (no entity expansion) and an oversized
 * document with a one-line reason.
 */

export interface XmlElement {
  type: "element";
  name: string;
  attrs: Array<[string, string]>;
  children: XmlNode[];
}
export type XmlNode = XmlElement | { type: "text"; text: string } | { type: "comment"; text: string };

export class XmlError extends Error {}

/** Larger documents are refused (a map of 50,000 lines is about 4 MB). */
export const MAX_XML_CHARS = 64 * 1024 * 1024;

const ENTITIES: Record<string, string> = { lt: "<", gt: ">", amp: "&", quot: '"', apos: "'" };
const NAME = /[A-Za-z_:][-A-Za-z0-9_:.]*/y;
const SPACE = /\s*/y;
const ATTR = /([A-Za-z_:][-A-Za-z0-9_:.]*)\s*=\s*("([^"]*)"|'([^']*)')/y;

function lineOf(src: string, at: number): number {
  let n = 1;
  for (let i = 0; i < at && i < src.length; i++) {
    n += src.charCodeAt(i) === 10 ? 1 : 0;
  }
  return n;
}

/** Entity and character references resolved (`src`, `at`: where, for the error's line). */
export function decode(s: string, src: string, at: number): string {
  if (!s.includes("&")) {
    return s; // the common case: no reference, no regular expression (issue 20: a 4 MB map's load)
  }
  return s.replace(/&(#x[0-9a-fA-F]+|#[0-9]+|[a-z]+);|&/g, (m, e: string | undefined) => {
    if (e === undefined) {
      throw new XmlError(`line ${lineOf(src, at)}: a bare '&'`);
    }
    if (e.startsWith("#")) {
      const code = e[1] === "x" ? parseInt(e.slice(2), 16) : parseInt(e.slice(1), 10);
      if (!(code > 0 && code <= 0x10ffff)) {
        throw new XmlError(`line ${lineOf(src, at)}: bad character reference ${m}`);
      }
      return String.fromCodePoint(code);
    }
    const v = ENTITIES[e];
    if (v === undefined) {
      throw new XmlError(`line ${lineOf(src, at)}: unknown entity ${m}`);
    }
    return v;
  });
}

/** Parse a document; its root element. XmlError with the line when it is not well-formed. */
export function parseXml(src: string): XmlElement {
  if (src.length > MAX_XML_CHARS) {
    throw new XmlError(`the document is too large (${src.length} characters, at most ${MAX_XML_CHARS})`);
  }
  let i = 0;
  const stack: XmlElement[] = [];
  let root: XmlElement | null = null;
  const fail = (what: string): never => {
    throw new XmlError(`line ${lineOf(src, i)}: ${what}`);
  };
  const until = (end: string, what: string): string => {
    const j = src.indexOf(end, i);
    if (j < 0) {
      fail(`unterminated ${what}`);
    }
    const s = src.slice(i, j);
    i = j + end.length;
    return s;
  };
  while (i < src.length) {
    const top = stack[stack.length - 1];
    if (src[i] !== "<") {
      const j = src.indexOf("<", i);
      const raw = src.slice(i, j < 0 ? src.length : j);
      if (top === undefined) {
        if (raw.trim() !== "") {
          fail("text outside the root element");
        }
      } else {
        top.children.push({ type: "text", text: decode(raw, src, i) });
      }
      i = j < 0 ? src.length : j;
    } else if (src.startsWith("<?", i)) {
      i += 2;
      until("?>", "processing instruction");
    } else if (src.startsWith("<!--", i)) {
      i += 4;
      const text = until("-->", "comment");
      top?.children.push({ type: "comment", text });
    } else if (src.startsWith("<![CDATA[", i)) {
      i += 9;
      const text = until("]]>", "CDATA section");
      (top ?? fail("text outside the root element")).children.push({ type: "text", text });
    } else if (src.startsWith("<!", i)) {
      fail("a DOCTYPE or declaration is not accepted");
    } else if (src.startsWith("</", i)) {
      i += 2;
      NAME.lastIndex = i;
      const m = NAME.exec(src) ?? fail("a closing tag without a name");
      i = NAME.lastIndex;
      SPACE.lastIndex = i;
      SPACE.exec(src);
      i = SPACE.lastIndex;
      if (src[i] !== ">") {
        fail(`'>' expected after </${m[0]}`);
      }
      i += 1;
      const open = stack.pop() ?? fail(`</${m[0]}> closes nothing`);
      if (open.name !== m[0]) {
        fail(`</${m[0]}> closes <${open.name}>`);
      }
    } else {
      i += 1;
      NAME.lastIndex = i;
      const m = NAME.exec(src) ?? fail("a tag without a name");
      i = NAME.lastIndex;
      const el: XmlElement = { type: "element", name: m[0], attrs: [], children: [] };
      for (;;) {
        SPACE.lastIndex = i;
        SPACE.exec(src);
        i = SPACE.lastIndex;
        ATTR.lastIndex = i;
        const a = ATTR.exec(src);
        if (a === null) {
          break;
        }
        if (el.attrs.some(([k]) => k === a[1])) {
          fail(`<${el.name}> repeats the attribute ${a[1]}`);
        }
        el.attrs.push([a[1], decode(a[3] ?? a[4], src, i)]);
        i = ATTR.lastIndex;
      }
      const selfClosing = src.startsWith("/>", i);
      if (!selfClosing && src[i] !== ">") {
        fail(`a malformed tag <${el.name}`);
      }
      i += selfClosing ? 2 : 1;
      if (top !== undefined) {
        top.children.push(el);
      } else if (root !== null) {
        fail("a second root element");
      } else {
        root = el;
      }
      if (!selfClosing) {
        stack.push(el);
      }
    }
  }
  if (stack.length > 0) {
    fail(`<${stack[stack.length - 1].name}> is not closed`);
  }
  return root ?? fail("no root element");
}

const escapeText = (s: string): string => s.replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;");
const escapeAttr = (s: string): string => escapeText(s).replace(/"/g, "&quot;");

/** Write an element; children that are only elements go one per line, indented by two spaces. */
export function writeXml(el: XmlElement, indent = ""): string {
  const attrs = el.attrs.map(([k, v]) => ` ${k}="${escapeAttr(v)}"`).join("");
  if (el.children.length === 0) {
    return `${indent}<${el.name}${attrs}/>`;
  }
  const blocky = el.children.some((c) => c.type === "element" && c.children.some((g) => g.type === "element"));
  const parts = el.children.map((c) =>
    c.type === "element"
      ? writeXml(c, blocky ? `${indent}  ` : "")
      : c.type === "comment"
        ? `${blocky ? `${indent}  ` : ""}<!--${c.text}-->`
        : escapeText(c.text),
  );
  if (blocky) {
    const lines = parts.filter((p, k) => el.children[k].type !== "text" || p.trim() !== "");
    return `${indent}<${el.name}${attrs}>\n${lines.join("\n")}\n${indent}</${el.name}>`;
  }
  return `${indent}<${el.name}${attrs}>${parts.join("")}</${el.name}>`;
}

/** A whole document: the XML declaration and the root. */
export function writeDocument(root: XmlElement): string {
  return `<?xml version="1.0" encoding="UTF-8"?>\n${writeXml(root)}\n`;
}

/** The element children of `el`, whitespace-only text and comments left out (for comparing documents). */
export function elementsOf(el: XmlElement): XmlElement[] {
  return el.children.filter((c): c is XmlElement => c.type === "element");
}
