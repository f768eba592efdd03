#!/usr/bin/env bash
# The test command: installs the dependencies, builds, and runs every test,
# first in Release, then under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/deploy/install-deps.sh"
bash "$ROOT/deploy/socket-buffers.sh"   # the multi-process tests carry camera images over LCM

bash "$ROOT/deploy/build.sh" release
(cd "$ROOT/build" && ctest --output-on-failure -j 2 -LE e2e)

# The end-to-end tests run one at a time and are made to hold with one core
# kept busy (tests/e2e), with nothing else running: a compiler beside them,
# even at nice 19 and idle I/O, made the closed-loop runs lose sensing on
# 2 cores. The sanitizer build comes after them.
(cd "$ROOT/build" && ctest --output-on-failure -L e2e)

bash "$ROOT/deploy/build.sh" asan
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
(cd "$ROOT/build-asan" && ctest --output-on-failure -j 2 -LE e2e)
# Under the sanitizers every process runs several times slower and the
# end-to-end tests take 11 minutes one after the other; these three run the
# code that reads the network and moves the tendons in every program of the
# pipeline (the services on a live rig, malformed messages on every input,
# the controller's faults). The others are the same programs in other
# arrangements, and their Release runs above check what they check.
ASAN_E2E='^(LivePipelineTest\.EveryShapeIsOfItsOwnTriggerWithinHalfAMillimetre|PipelineFaultsTest\.MalformedMessagesAreRejectedAndCountedAndMeasuringGoesOn|ControllerFaultsTest\..*)$'
(cd "$ROOT/build-asan" && ctest --output-on-failure -L e2e -R "$ASAN_E2E")
