#!/usr/bin/env bash
# Installs the systemd units of one rig host and starts them:
#   deploy/rig/install.sh [--dry-run] [--no-start] DIR
# DIR holds the units `shapesense rig units FILE --host NAME --out DIR` wrote
# (or copies of deploy/systemd/*@.service templates). Each DIR/*.service is
# checked (systemd-analyze verify), copied to /etc/systemd/system, then
# systemd reloads and every unit is enabled and started (--no-start: enabled
# only). --dry-run prints what would be done and changes nothing.
set -euo pipefail

usage() { echo "usage: deploy/rig/install.sh [--dry-run] [--no-start] DIR" >&2; exit 2; }
fail() { echo "install.sh: error: $*" >&2; exit 1; }

DRY_RUN=0
START=1
DIR=""
while [ $# -gt 0 ]; do
  case "$1" in
    --dry-run) DRY_RUN=1 ;;
    --no-start) START=0 ;;
    -h|--help) usage ;;
    -*) echo "install.sh: unknown option '$1'" >&2; usage ;;
    *) [ -z "$DIR" ] || usage; DIR="$1" ;;
  esac
  shift
done
[ -n "$DIR" ] || usage
[ -d "$DIR" ] || fail "'$DIR' is not a folder of unit files"

TARGET="${SYSTEMD_UNIT_DIR:-/etc/systemd/system}"
shopt -s nullglob
UNITS=("$DIR"/*.service)
[ ${#UNITS[@]} -gt 0 ] || fail "no *.service file in '$DIR'"

run() {
  if [ "$DRY_RUN" -eq 1 ]; then
    echo "would run: $*"
  else
    echo "+ $*"
    "$@"
  fi
}

# A template (name@.service) is installed but not started: it needs an instance.
startable=()
for unit in "${UNITS[@]}"; do
  name="$(basename "$unit")"
  [[ "$name" == *@.service ]] || startable+=("$name")
done

if [ "$DRY_RUN" -eq 0 ]; then
  [ "$(id -u)" -eq 0 ] || fail "installing into $TARGET needs root (or try --dry-run)"
  command -v systemctl > /dev/null || fail "systemctl not found: this host does not run systemd"
fi
if command -v systemd-analyze > /dev/null; then
  for unit in "${UNITS[@]}"; do
    [[ "$(basename "$unit")" == *@.service ]] && continue
    said="$(systemd-analyze verify "$unit" 2>&1 | grep -F "$(basename "$unit")" || true)"
    [ -z "$said" ] || fail "systemd-analyze verify on $unit: $said"
  done
else
  echo "install.sh: systemd-analyze not found; installing the units unchecked" >&2
fi

for unit in "${UNITS[@]}"; do
  run install -m 0644 "$unit" "$TARGET/$(basename "$unit")"
done
run systemctl daemon-reload
if [ ${#startable[@]} -gt 0 ]; then
  if [ "$START" -eq 1 ]; then
    run systemctl enable --now "${startable[@]}"
  else
    run systemctl enable "${startable[@]}"
  fi
fi
[ "$DRY_RUN" -eq 1 ] && echo "install.sh: dry run, nothing changed"
exit 0
