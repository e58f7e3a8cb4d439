#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs every Debian bookworm package vinebot needs to build, test and run.
# Idempotent and quiet: it only calls apt-get when something is missing.
# Usage: deploy/setup.sh            (as root, or with sudo available)
set -euo pipefail

packages=(
  # toolchain
  g++ cmake ninja-build pkg-config ccache make
  # core
  libeigen3-dev nlohmann-json3-dev libabsl-dev
  # vision (per-module OpenCV packages: the meta package pulls in far more than we use)
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-calib3d-dev
  # reconstruction: joint 3D optimisation
  libceres-dev
  # planning: RRT-Connect and the FCL collision-checking baseline
  libompl-dev libfcl-dev
  # cameras: Aravis (GigE Vision / USB3 Vision); its pkg-config file needs libusb's;
  # aravis-tools provides arv-fake-gv-camera-0.8, which the camera tests start on loopback
  libaravis-dev libusb-1.0-0-dev aravis-tools
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "deploy/setup.sh: installing ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "deploy/setup.sh: done"
