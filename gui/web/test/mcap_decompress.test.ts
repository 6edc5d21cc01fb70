import { McapStreamReader, type McapTypes } from "@mcap/core";
import { describe, expect, it } from "vitest";
import { decompressHandlers } from "../src/session/mcap_decompress";
import { mcapFile } from "./mcap_file";

// what pltf export writes its chunks with: python-lz4's lz4.frame.compress (linked 64 KB blocks) and
// python-zstandard at level 1, of the text below (fixed bytes, made once)
const PY_LZ4 =
  "04224d184840605b03000000000016a0020000b5706c74662030303030303b0b0016310b0016320b0016330b0016340b0016350b0016360b0016370b0016380b0015390b0016316e0016316e0016316e0016316e0016316e0016316e0016316e0016316e0016316e0016316e0016326e0016326e0016326e0016326e0016326e0016326e0016326e0016326e0016326e0016326e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016396e000f4c04ffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffff905020303030350e010000153794ff0f84fdffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffde507466203030a0020000e63031353b706c74662030303031360b0016370b0016380b0015390b002632300b0016310b0016320b0016330b0016340b00066e0016326e0016326e0016326e0016326e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016336e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016346e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016356e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016366e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016376e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016386e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016396e0016306e0016306e0016306e0016306e0016306e0016306e0016306e0016306e0016306e0016306e0016316e00253131bd0316316e0016316e0016316e000f4c04ffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffff9750706c746620650000000f84fdffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffa350303039393b00000000";
const PY_ZSTD =
  "28b52ffd60f0544d27002a8a900f11d0653840810a6bb724a5943225ea800801f400f300f3002ef7178d84cbd58b46c2e5e84523e172f3a291703979d148b85cbc68245cce2f1a0997eb8b46c2e5f8a29170b9bd68245cee2f1a0997ab178d84cbd18b46c2e5e64523e172f2a29170b978d148b89c5f34122ed7178d84cbf14523e1727bd148b8dc5f34122e572f1a0997a3178d84cbcd8b46c2e5e44523e172f1a2917039bf68245cae2f1a0997e38b46c2e5f6a29170b9bf68245cae5e34122e472f1a09979b178d84cbc98b46c2e5e24523e1727ed148b85c5f34122ec7178d84cbed4523e1727fd148b85cbd68245c8e5e34122e372f1a099793178d84cbc58b46c2e5fca29170b9be68245c8e2f1a0997c3b64d000c028223e1727fd148b85cbd68245c8e5e34122e372f1a099793178d84cbc58b46c2e5fca29170b9be68245c8e2f1a0997db8b46c2e5fea29170b97ad148b81cbd68245c6e5e34122e272f1a09978b178d84cbf94523e1727dd148b81c5f34122eb7178d84cbfd4523e172f5a29170397ad148b8dcbc68245c4e5e34122e172f1a0997f38b46c2e5faa2917039be68245c6e2f1a0997fb8b46c2e5ea4523e172f4a29170b979d148b89cbc68245c2e5e34122ee7178d84cbf54523e1727cd148b8dc5e34122ef7178d84cbd58b46c2e5e84523e172f3a291703979d148b85cbc68245cce2f1a0997eb8b46c2e5f8a29170b9bd6824022f1a0997fb8b46c2e5ea4523e172f4a29170b979d148b89cbc68245c2e5e34122ee7178d84cbf54523e1727cd148b8dc5e34122ef7178d84cbd58b46c2e5e84523e172f3a291703979d148b85cbc68245cce2f1a0997eb8b46c2e5f8a29170b9bd68245cee2f1a0997ab178d84cbd18b46c2e5e64523e172f2a29170b978d148b89c5f34122ed7178d84cbf14523e1727bd148b8dc5f34122e572f1a0997a3178d84cbcd8b46c2e5e44523e172f1a2917039bf68245cae2f1a0997e38b46c2e5f6a29170b9bf68245cae5e34122e472f1a09979b178d84cbc98b46c2e5e24523e1727ed148b85c5f34122ec7178d84cbed4501c38b46c2e5fea29170b97ad148b81cbd68245c6e5e34122e272f1a09978b178d84cbf94523e1727dd148b81c5f34122eb7178d84cbfd4523e172f5a29170397ad148b8dcbc68245c4e5e34122e172f1a0997f38b46c2e5faa2917039be68245c6e2f1a0997fb8b46c2e5ea4523e172f4a29170b979d148b89cbc68245c2e5e34122ee7178d84cbf54523e1727cd148b8dc5e34122ef7178d84cbd58b46c2e5e84523e172f3a291703979d148b85cbc68245cce2f1a0997eb8b46c2e5f8a29170b9bd68245cee2f1a0997ab178d84cbd18b46c2e5e64523e172f2a29170b978d148b89c5f34122ed7178d84cbf14523e1720b87cfa813c0b9ef1be3bf0613b01aff6d4a7110002ad013e022fd0155dc0a74a55a03d25c5b808bf40754712bd0956a0d48bbb60017e90f50c5ad4057aa3520edda025ca43fa08a5b81ae546b80b46b0b7091fe802a6e05ba52ad0169d716e022dd03aab815e84ab506a45d5b808bf40754712bd0956a1a90766d012ed21f50c5ad4057aa3520edda025c487f4015b7025da9d680b46b0b7091fe802a6e0572a55a03d2ae2dc045fa03aab815e84ab506a45d5b0017e90fa8e256a02bd51a90766d012ed21f50c54d81ae546b40dab505b8487f4015b7025da9d680b46b16e022fd0155dc0a74a55a03d2ae2dc045fa03aa702bd0956a0d48bbb6c0949819a6ab2b";

function fromHex(hex: string): Uint8Array {
  return Uint8Array.from(hex.match(/../g) ?? [], (h) => Number.parseInt(h, 16));
}

function text(items: number): Uint8Array {
  let s = "";
  for (let i = 0; i < items; i++) s += `pltf ${String(i % 100).padStart(5, "0")};`;
  return new TextEncoder().encode(s);
}

function read(file: Uint8Array): { chunks: string[]; messages: number[] } {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(file);
  const chunks: string[] = [];
  const messages: number[] = [];
  for (let rec: McapTypes.TypedMcapRecord | undefined; (rec = reader.nextRecord()) !== undefined; ) {
    if (rec.type === "ChunkIndex") chunks.push(rec.compression);
    if (rec.type === "Message") messages.push(JSON.parse(new TextDecoder().decode(rec.data)).i);
  }
  expect(reader.done()).toBe(true);
  return { chunks, messages };
}

describe("the MCAP decompress handlers", () => {
  it("read python-lz4's frames of linked blocks, as pltf export --compression lz4 writes them", () => {
    const want = text(20000); // 220,000 bytes: four 64 KB blocks, each referring back into the one before
    expect(decompressHandlers.lz4(fromHex(PY_LZ4), BigInt(want.length))).toEqual(want);
  });

  it("read python-zstandard's level 1, as pltf export writes by default", () => {
    const want = text(2000);
    expect(decompressHandlers.zstd(fromHex(PY_ZSTD), BigInt(want.length))).toEqual(want);
  });

  it("refuse a chunk whose size is not the one its record gives, naming both", () => {
    expect(() => decompressHandlers.lz4(fromHex(PY_LZ4), 219999n)).toThrow(/lz4.*220000 bytes.*says 219999/);
    expect(() => decompressHandlers.lz4(fromHex(PY_LZ4), 220001n)).toThrow(/220000 bytes.*says 220001/);
  });

  it("let @mcap/core read every message of lz4 and uncompressed chunks, CRCs checked", async () => {
    for (const compression of ["lz4", ""] as const) {
      const got = read(await mcapFile(compression, 2000));
      expect(got.messages).toEqual([...Array(2000).keys()]);
      expect(got.chunks.length).toBeGreaterThan(3);
      expect(new Set(got.chunks)).toEqual(new Set([compression]));
    }
  });
});
