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

/** A file name for a document named `name` (the platform's name, or "map"/"roadmap"), with its extension. */
export function fileNameOf(name: string, fallback: string, ext: string): string {
  const base = name.replace(/[\\/:*?"<>|]+/g, "_").trim() || fallback;
  return base.endsWith(ext) ? base : `${base}${ext}`;
}
