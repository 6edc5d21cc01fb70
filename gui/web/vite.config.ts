// Build of the GUI's front end: `npm run build` (called by `make gui`) writes gui/static/.
import { fileURLToPath } from "node:url";
import { defineConfig } from "vite";

const client = fileURLToPath(new URL("../../clients/generated/typescript/src", import.meta.url));

export default defineConfig({
  base: "./",
  resolve: { alias: { "@pltf": client } },
  build: {
    outDir: fileURLToPath(new URL("../static", import.meta.url)),
    emptyOutDir: true,
    target: "es2022",
    sourcemap: true,
    chunkSizeWarningLimit: 2000,
  },
  test: { include: ["test/**/*.test.ts"], environment: "node" },
});
