import { h } from "../dom";
import { bind, type Key, t } from "../i18n/i18n";
import { MAX_XML_CHARS } from "./xml";

export { fileNameOf } from "./shell";

/** guide 5.4/5.5 "Save the current map (roadmap) to the local harddrive": the document as a download. */
export function download(fileName: string, text: string): void {
  const url = URL.createObjectURL(new Blob([text], { type: "application/xml" }));
  const a = document.createElement("a");
  a.href = url;
  a.download = fileName;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

/** guide 5.4/5.5 "Load a map (roadmap) from the hard disk": the editors' file input. A file over MAX_XML_CHARS is
 * refused with its size; otherwise `load` gets the file's name and text, and reports what it made of them. */
export function fileInput(
  accept: string,
  key: Key,
  say: (text: string) => void,
  load: (fileName: string, text: string) => void,
): HTMLInputElement {
  const file = h("input", { type: "file", accept });
  bind(file, key, { text: false });
  file.addEventListener("change", () => {
    const f = file.files?.[0];
    file.value = "";
    if (f === undefined) {
      return;
    }
    if (f.size > MAX_XML_CHARS) {
      say(t("edit.openFailed", { file: f.name, why: `${f.size} bytes is over ${MAX_XML_CHARS}` }));
      return;
    }
    void f.text().then((text) => load(f.name, text));
  });
  return file;
}
