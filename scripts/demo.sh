#!/usr/bin/env bash
# The main job, end to end on the simulated dome, from a fresh machine:
# installs what is missing, builds, then `lightstage demo` starts the simulated
# dome's programs (lightstage-sim, lightstage-domed), calibrates the lights from
# a chrome sphere, captures the object, solves, integrates and writes the report.
#   scripts/demo.sh [OUT_DIR]      (default: out/demo)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" release
exec "$root/build/bin/lightstage" demo --out "${1:-$root/out/demo}"
