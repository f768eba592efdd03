#!/usr/bin/env bash
# The main job: installs the dependencies, builds, and runs the end-to-end demo
# on the virtual rig (no hardware). Output in demo-output/ (or the folder given).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/demo-output}"
bash "$ROOT/deploy/install-deps.sh"
bash "$ROOT/deploy/build.sh" release
"$ROOT/build/bin/shapesense" demo --out "$OUT"
