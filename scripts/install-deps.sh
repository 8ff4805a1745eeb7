#!/usr/bin/env bash
# Installs the Debian bookworm packages mrpt_wifi needs to build and test.
# Runs as root or through sudo; does nothing when everything is already there.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config clang clang-format libclang-rt-14-dev
  libmrpt-dev mrpt-apps
  libeigen3-dev libceres-dev libopencv-dev
  libgtest-dev libgmock-dev libbenchmark-dev libpcap-dev
  openssh-server openssh-client tcpdump
  gnuplot-nox
  librosbag-dev pluginlib-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
  python3-rosbag python3-genpy python3-rostopic
  xvfb xauth libgl1-mesa-dri
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
