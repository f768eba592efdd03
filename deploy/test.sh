#!/usr/bin/env bash
# The test command: installs the dependencies, builds, and runs every test,
# first in Release, then under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/deploy/install-deps.sh"
bash "$ROOT/deploy/socket-buffers.sh"   # the multi-process tests carry camera images over LCM

bash "$ROOT/deploy/build.sh" release
(cd "$ROOT/build" && ctest --output-on-failure -j 2)

bash "$ROOT/deploy/build.sh" asan
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
(cd "$ROOT/build-asan" && ctest --output-on-failure -j 2)
