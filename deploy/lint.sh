#!/usr/bin/env bash
# Checks formatting (every source) and clang-tidy: deploy/lint.sh [--since REV]
#   (no option)  clang-tidy on every source file (about 25 min on 2 cores);
#   --since REV  clang-tidy on the sources changed since REV (added, modified,
#                or moved and edited), and on the .cc beside each changed
#                header. CI runs this with REV = deploy/lint-baseline, the
#                last commit that landed.
# Needs a Release build tree for compile_commands.json (deploy/build.sh release).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
JOBS="${JOBS:-$(nproc)}"

mapfile -t FILES < <(git ls-files '*.cc' '*.h')
clang-format --dry-run --Werror "${FILES[@]}"
echo "lint: clang-format: ${#FILES[@]} files formatted"

changed_since() {
  git diff --name-status -M "$1" HEAD |
    awk '$1 == "A" || $1 == "M" { print $2 } $1 ~ /^R/ && $1 != "R100" { print $3 }'
}

if [[ "${1:-}" == "--since" ]]; then
  BASE="${2:?usage: deploy/lint.sh [--since REV]}"
  if ! git rev-parse --quiet --verify "$BASE^{commit}" > /dev/null; then
    # A shallow clone lacks the baseline: the last commit's files at least.
    echo "lint: $BASE is not in this clone's history; checking the files of HEAD only" >&2
    mapfile -t CHANGED < <(git show --name-only --format= HEAD)
  else
    mapfile -t CHANGED < <(changed_since "$BASE")
  fi
  SOURCES=()
  for file in "${CHANGED[@]}"; do
    [[ -f "$file" ]] || continue
    case "$file" in
      *.cc) SOURCES+=("$file") ;;
      *.h) [[ -f "${file%.h}.cc" ]] && SOURCES+=("${file%.h}.cc") ;;
    esac
  done
  mapfile -t SOURCES < <(printf '%s\n' "${SOURCES[@]}" | sort -u | sed '/^$/d')
  echo "lint: clang-tidy on ${#SOURCES[@]} sources changed since $BASE"
else
  mapfile -t SOURCES < <(printf '%s\n' "${FILES[@]}" | grep '\.cc$')
  echo "lint: clang-tidy on all ${#SOURCES[@]} sources"
fi
[[ ${#SOURCES[@]} -gt 0 ]] || exit 0
# One file per call, $JOBS at once; any warning (they are errors) fails.
printf '%s\0' "${SOURCES[@]}" | xargs -0 -n 1 -P "$JOBS" clang-tidy -p build --quiet
echo "lint: clang-tidy clean"
