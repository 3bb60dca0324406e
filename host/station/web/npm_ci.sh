#!/usr/bin/env bash
# Installs the page's npm packages (package-lock.json: preact, htm, esbuild)
# into DEST, a folder of the build tree. A no-op when DEST holds this lock.
#   host/station/web/npm_ci.sh SOURCE_DIR DEST
set -euo pipefail
src=$1
dest=$2
mkdir -p "$dest"
if cmp -s "$src/package-lock.json" "$dest/package-lock.json" && [ -f "$dest/node_modules/esbuild/package.json" ]; then
  exit 0
fi
cp "$src/package.json" "$src/package-lock.json" "$dest/"
npm ci --prefix "$dest" --ignore-scripts --no-audit --no-fund --loglevel=error
