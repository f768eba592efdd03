#!/usr/bin/env bash
# Lets LCM receivers of camera images have the 4 MB socket buffers they ask
# for (recv_buf_size in their URLs, docs/capture.md): the kernel caps them at
# net.core.rmem_max, 208 KB by default, which loses images. Global, so it
# also holds inside the network namespaces the tests and the demo make.
set -euo pipefail
WANTED=4194304
if [ "$(cat /proc/sys/net/core/rmem_max)" -lt "$WANTED" ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "raising net.core.rmem_max to $WANTED (socket buffers for camera images)"
  $SUDO sysctl -q -w net.core.rmem_max="$WANTED" ||
    echo "could not raise net.core.rmem_max; expect lost camera images" >&2
fi
