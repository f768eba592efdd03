#!/usr/bin/env bash
# Checks formatting and clang-tidy on the project's sources (needs a Release
# build tree for compile_commands.json: deploy/build.sh release).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
mapfile -t FILES < <(git ls-files '*.cc' '*.h' | grep -v '^build')
clang-format --dry-run --Werror "${FILES[@]}"
mapfile -t SOURCES < <(printf '%s\n' "${FILES[@]}" | grep '\.cc$')
clang-tidy -p build --quiet "${SOURCES[@]}"
