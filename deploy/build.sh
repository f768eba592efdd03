#!/usr/bin/env bash
# Configures and builds one build tree: deploy/build.sh [release|asan] [TARGET...]
# (default: everything; `programs`: the shipped programs alone, no tests).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
KIND="${1:-release}"
shift || true
JOBS="${JOBS:-$(nproc)}"
case "$KIND" in
  release) DIR="$ROOT/build"; FLAGS=(-DCMAKE_BUILD_TYPE=Release) ;;
  # -O1 -g1: quicker to build than -O2 -g, fast enough to run, with line numbers.
  asan) DIR="$ROOT/build-asan"; FLAGS=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DSHAPESENSE_SANITIZE=ON -DSHAPESENSE_BUILD_BENCH=OFF) ;;
  *) echo "usage: deploy/build.sh [release|asan] [TARGET...]" >&2; exit 2 ;;
esac
cmake -S "$ROOT" -B "$DIR" -G Ninja "${FLAGS[@]}" > /dev/null
ninja -C "$DIR" -j "$JOBS" "$@"
