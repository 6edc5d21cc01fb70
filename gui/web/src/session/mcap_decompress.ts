/**
 * The decompress handlers an MCAP reader of @mcap/core (McapIndexedReader, McapStreamReader) needs for the files
 * `pltf export --mcap` and `pltf proxy --mcap` write (proxy/mcap_writer.py): each chunk compressed with zstd (the
 * default; fzstd), with lz4 (`--compression lz4`: the LZ4 frame format; lz4js) or not at all (`--compression
 * none`: a chunk whose compression is "" needs no handler). Foxglove reads the same three.
 *
 * A chunk that does not come out at the size its record gives is an error naming both sizes (lz4js itself would
 * return a shorter buffer, or drop what does not fit).
 */
import type { McapTypes } from "@mcap/core";
import { decompress as unzstd } from "fzstd";
import { decompress as unlz4 } from "lz4js";

function sized(out: Uint8Array, size: bigint, compression: string): Uint8Array {
  if (BigInt(out.length) !== size) {
    throw new Error(`an MCAP chunk (${compression}) decompressed to ${out.length} bytes, its record says ${size}`);
  }
  return out;
}

export const decompressHandlers: McapTypes.DecompressHandlers = {
  zstd: (buf, size) => sized(unzstd(buf, new Uint8Array(Number(size))), size, "zstd"),
  lz4: (buf, size) => sized(unlz4(buf, Number(size) + 1), size, "lz4"), // one spare byte: a longer chunk shows
};
