#!/bin/sh
# sh build.sh: copy the generated TypeScript client into src/platformctrl (PLATFORMCTRL: its folder, default the
# toolkit's clients/generated/typescript; or `pltf stubs --lang typescript --out DIR`), install typescript and
# @types/node (npm, pinned in package.json; from the cache when there), compile with tsc into dist/.
# Run: node dist/patrol.js --target HOST:PORT --stations A,B,C
set -e
cd "$(dirname "$0")"
GEN="${PLATFORMCTRL:-../../clients/generated/typescript}"
rm -rf src/platformctrl
mkdir -p src/platformctrl
cp "$GEN"/src/*.ts src/platformctrl/
[ -x node_modules/.bin/tsc ] || npm install --no-audit --no-fund --prefer-offline --loglevel=error >/dev/null
node_modules/.bin/tsc -p .
