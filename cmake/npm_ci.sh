#!/usr/bin/env bash
# Installs a page's npm packages (SOURCE_DIR/package-lock.json) into DEST, a
# folder of the build tree, for the build to bundle or embed. A no-op when
# DEST already holds this lock, installed (npm's node_modules/.package-lock.json).
#   cmake/npm_ci.sh SOURCE_DIR DEST
set -euo pipefail
src=$1
dest=$2
mkdir -p "$dest"
if cmp -s "$src/package-lock.json" "$dest/package-lock.json" && [ -f "$dest/node_modules/.package-lock.json" ]; then
  exit 0
fi
cp "$src/package.json" "$src/package-lock.json" "$dest/"
npm ci --prefix "$dest" --ignore-scripts --no-audit --no-fund --loglevel=error
