#!/usr/bin/env bash
# Installs every Debian package the project needs to build, test and run the
# demo. Idempotent: when everything is present it changes nothing and makes
# no network request. Needs root (or sudo) only when something is missing.
#
#   deploy/setup.sh            build + test + demo dependencies
#   deploy/setup.sh --print    list the packages and exit
set -euo pipefail
case "${1:-}" in
  "" | --print) ;;
  -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  *) echo "setup: unknown option '$1' (see --help)" >&2; exit 2 ;;
esac

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config clang-format
  # DDS (C library, idlc, ddsperf)
  cyclonedds-dev cyclonedds-tools
  # libraries
  libeigen3-dev libprotobuf-dev protobuf-compiler libspdlog-dev libsqlite3-dev
  zlib1g-dev libcli11-dev
  # tests and benchmarks; clang with libFuzzer for the fuzz targets (deploy/fuzz.sh)
  libgtest-dev libgmock-dev libbenchmark-dev sqlite3 clang libclang-rt-14-dev
  # benchmarks: cyclictest beside the edge loop
  rt-tests
  # dashboard: Boost.Beast (headers), the page's npm packages, the browser test
  libboost-dev ca-certificates chromium
  # OpenSSL: the dashboard's token hashes (libcrypto); the DDS Security PKI (deploy/security)
  libssl-dev openssl
  # LinuxCNC 2.9 (uspace): rs274 checks the G-code; the real-CNC drive and
  # its headless machine (deploy/linuxcnc/). Recommends are not installed
  # (they pull a realtime kernel, PyQt and OpenCV).
  linuxcnc-uspace linuxcnc-uspace-dev
  # containerised integration tests (tests/integration/containers)
  podman podman-compose debootstrap runc curl
)
# Node.js and npm: Debian's, unless the machine already has them (a Node.js
# from elsewhere bundles its own npm and conflicts with Debian's npm package).
command -v node >/dev/null || packages+=(nodejs)
command -v npm >/dev/null || packages+=(npm)

if [[ "${1:-}" == "--print" ]]; then
  printf '%s\n' "${packages[@]}"
  exit 0
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then
    sudo_cmd=(sudo)
  else
    echo "setup: missing packages (${missing[*]}) and not root; run as root" >&2
    exit 1
  fi
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
# Refresh the package lists only when they are absent or a day old.
if [[ -z "$(find /var/lib/apt/lists -maxdepth 1 -name '*_Packages' -mmin -1440 2>/dev/null | head -n1)" ]]; then
  "${sudo_cmd[@]}" apt-get update -q
fi
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
