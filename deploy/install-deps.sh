#!/usr/bin/env bash
# Installs every dependency of shapesense on Debian 12. Idempotent: installs
# only what is missing, and touches nothing when all is there.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libopencv-dev libopencv-contrib-dev opencv-doc
  libeigen3-dev libceres-dev
  liblcm-dev liblcm-bin
  libaravis-dev aravis-tools libusb-1.0-0-dev
  libv4l-dev v4l-utils
  libyaml-cpp-dev libcli11-dev libspdlog-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev
  iproute2 socat
  libsystemd-dev systemd
  libssl-dev
  libboost-dev libjs-three
  chromium
  clang-format clang-tidy
)

# Node.js and npm run the browser test's driver (playwright-core, from
# tests/browser's lock file); Debian's when the machine has none of its own.
if ! command -v node > /dev/null || ! command -v npm > /dev/null; then
  PACKAGES+=(nodejs npm)
fi

missing=()
for package in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages are installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
