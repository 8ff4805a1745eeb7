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
  libzstd-dev liblz4-dev lz4 libsqlite3-dev libfastcdr-dev nodejs
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# npm comes with NodeSource's nodejs package and separately with Debian's.
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Independent MCAP and CDR implementations for the ROS 2 tests (they write bags this project
# imports and read what it exports): pinned versions, into the build folder, not the repository.
npm_dir=build/npm-tools
npm_packages="@mcap/core@2.2.2 @foxglove/cdr@3.5.0 @foxglove/rosmsg@5.0.5 @foxglove/rosmsg2-serialization@3.1.0 @foxglove/wasm-zstd@1.0.1 @foxglove/wasm-lz4@1.0.2"
if [ "$(cat "$npm_dir/.installed" 2>/dev/null)" != "$npm_packages" ]; then
  echo "install-deps: npm packages into $npm_dir: $npm_packages"
  mkdir -p "$npm_dir"
  # shellcheck disable=SC2086  # the package list is split on purpose
  npm install --prefix "$npm_dir" --no-save --no-audit --no-fund --loglevel=error $npm_packages
  echo "$npm_packages" >"$npm_dir/.installed"
fi
