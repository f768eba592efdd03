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
# kept busy (tests/e2e): meanwhile the sanitizer build takes what CPU they
# leave, at the lowest priority (nice 19, idle I/O), so that it never
# competes with the pipeline under test (on 2 cores, a compiler at normal
# priority beside a test's own busy core starves the virtual rig). It runs
# in a process group of its own (its output in build-asan/background.log),
# stopped once they are done; then it goes on with every core.
mkdir -p "$ROOT/build-asan"
JOBS=1 setsid nice -n 19 ionice -c 3 bash "$ROOT/deploy/build.sh" asan \
  > "$ROOT/build-asan/background.log" 2>&1 &
ASAN_BUILD=$!
stop_asan_build() {
  kill -INT -- "-$ASAN_BUILD" 2> /dev/null || true
  wait "$ASAN_BUILD" 2> /dev/null || true
}
trap stop_asan_build EXIT
(cd "$ROOT/build" && ctest --output-on-failure -L e2e)
stop_asan_build
trap - EXIT

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
