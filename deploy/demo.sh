#!/usr/bin/env bash
# The main job: installs the dependencies, builds, and runs the live demo on
# the virtual rig (no hardware): the pipeline as separate programs over LCM,
# in a private network namespace where it can make one, for 20 s; it prints
# latency per stage and accuracy against the rig's truth, and leaves an LCM
# log that `shapesense replay` and lcm-logplayer accept.
#   bash deploy/demo.sh [OUT] [shapesense demo options, e.g. --duration 10]
# Output in OUT (default demo-output/).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/demo-output"
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then
  OUT="$1"
  shift
fi
bash "$ROOT/deploy/install-deps.sh"
# The programs alone: the tests (most of the targets) are deploy/test.sh's.
bash "$ROOT/deploy/build.sh" release programs

bash "$ROOT/deploy/socket-buffers.sh"
"$ROOT/build/bin/shapesense" demo --out "$OUT" "$@"
