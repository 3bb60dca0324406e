#!/usr/bin/env bash
# Installs the browser test's npm packages (package-lock.json, playwright-core
# only: it drives Debian's /usr/bin/chromium and downloads no browser) into
# DEST, a folder of the build tree. A no-op when DEST already holds this lock.
#   tests/report/npm_ci.sh SOURCE_DIR DEST
set -euo pipefail
src=$1
dest=$2
mkdir -p "$dest"
if cmp -s "$src/package-lock.json" "$dest/package-lock.json" && [ -f "$dest/node_modules/playwright-core/package.json" ]; then
  exit 0
fi
cp "$src/package.json" "$src/package-lock.json" "$dest/"
export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1
npm ci --prefix "$dest" --ignore-scripts --no-audit --no-fund --loglevel=error
