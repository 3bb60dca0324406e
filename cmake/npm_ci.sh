#!/usr/bin/env bash
# Installs npm packages (SOURCE_DIR/package-lock.json) into DEST, a folder of
# the build tree: the pages' (bundled or embedded by the build) and the
# browser test's (playwright-core, which drives Debian's chromium: no browser
# is downloaded, and no package's install scripts run). A no-op when DEST
# already holds this lock, installed (npm's node_modules/.package-lock.json).
#   cmake/npm_ci.sh SOURCE_DIR DEST
set -euo pipefail
src=$1
dest=$2
mkdir -p "$dest"
if cmp -s "$src/package-lock.json" "$dest/package-lock.json" && [ -f "$dest/node_modules/.package-lock.json" ]; then
  exit 0
fi
cp "$src/package.json" "$src/package-lock.json" "$dest/"
export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1
npm ci --prefix "$dest" --ignore-scripts --no-audit --no-fund --loglevel=error
