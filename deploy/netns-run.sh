#!/usr/bin/env bash
# Runs a command inside a private network namespace whose only interface is
# a multicast-capable loopback, so LCM's UDP multicast and the fake GigE
# cameras never leave it:  deploy/netns-run.sh COMMAND [ARGS...]
# Works as root or as a user allowed user namespaces (unshare -r).
set -euo pipefail
if [ "${SHAPESENSE_IN_NETNS:-}" = "1" ]; then
  exec "$@"
fi
inner='ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$@"'
if [ "$(id -u)" -eq 0 ]; then
  exec unshare -n env SHAPESENSE_IN_NETNS=1 bash -c "$inner" netns "$@"
fi
exec unshare -rn env SHAPESENSE_IN_NETNS=1 bash -c "$inner" netns "$@"
