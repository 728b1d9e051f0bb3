#!/usr/bin/env bash
# The Debian packages of the smc image's two stages, and their installation.
# Runs inside the image build (deploy/Containerfile) and on the host (to list
# what the offline build needs).
#
#   packages.sh list build|runtime      print the packages, one per line
#   packages.sh install build|runtime   install them (no-op when present)
#
# install takes the .deb files in $SMC_DEBS/build or $SMC_DEBS/runtime
# (SMC_DEBS defaults to /var/cache/smc-debs) when that folder holds any: the test harness downloads them on the host and
# builds with --network=none, so no container reaches a package mirror.
# Without them it uses apt-get and the image's own sources (a build machine
# with network access to a Debian mirror).
set -euo pipefail

build_packages=(
  build-essential cmake ninja-build pkg-config ccache
  cyclonedds-dev cyclonedds-tools
  libeigen3-dev libprotobuf-dev protobuf-compiler libspdlog-dev libsqlite3-dev
  zlib1g-dev libcli11-dev
  # dashboard: Boost.Beast (headers), npm for the page's one dependency,
  # libcrypto for its token hashes
  libboost-dev nodejs npm libssl-dev
)
# What smc-cell, smc-edge and smc-dashboard load (ldd), nothing else.
runtime_packages=(
  libddsc0debian libprotobuf32 libspdlog1.10 libfmt9 libsqlite3-0 zlib1g libstdc++6 libssl3
)

usage() {
  echo "usage: $0 list|install build|runtime" >&2
  exit 2
}

[[ $# -eq 2 ]] || usage
case "$2" in
  build) packages=("${build_packages[@]}") ;;
  runtime) packages=("${runtime_packages[@]}") ;;
  *) usage ;;
esac

case "$1" in
  list)
    printf '%s\n' "${packages[@]}"
    ;;
  install)
    missing=()
    for p in "${packages[@]}"; do
      dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [[ ${#missing[@]} -eq 0 ]]; then
      echo "packages: all ${#packages[@]} present"
      exit 0
    fi
    export DEBIAN_FRONTEND=noninteractive
    debs_dir=${SMC_DEBS:-/var/cache/smc-debs}/$2
    shopt -s nullglob
    debs=("$debs_dir"/*.deb)
    if [[ ${#debs[@]} -gt 0 ]]; then
      echo "packages: installing ${missing[*]} from ${#debs[@]} local .deb files (offline)"
      apt-get install -y -q --no-install-recommends "${debs[@]}"
    else
      echo "packages: installing ${missing[*]} from the network"
      apt-get update -q
      apt-get install -y -q --no-install-recommends "${missing[@]}"
    fi
    # Every package asked for must be there now (a short local set fails here).
    for p in "${packages[@]}"; do
      dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" ||
        { echo "packages: $p is still missing" >&2; exit 1; }
    done
    apt-get clean
    rm -rf /var/lib/apt/lists/*
    ;;
  *) usage ;;
esac
