# shellcheck shell=bash
# The container image of the tests, built without any image registry:
#
#   1. a Debian 12 root filesystem by debootstrap --variant=minbase, from the
#      mirror of this machine's own apt sources, imported with podman import;
#   2. the .deb files of the image's two stages, downloaded on the host by
#      apt (against the root filesystem's dpkg status), and the dashboard
#      page's npm packages in an npm cache;
#   3. deploy/Containerfile built on top with --network=none, the .debs and
#      the npm cache mounted into the build.
#
# Everything is cached under $SMC_CT_CACHE (default /var/cache/smc-containers,
# never in the repository) and in podman's image store, keyed by content
# hashes: a second run with unchanged sources builds nothing, and a change
# recompiles only what ccache (also kept there) has not seen.
# Needs: ROOT (repository), RUN_DIR (logs), common.sh.

CACHE=${SMC_CT_CACHE:-/var/cache/smc-containers}

# Debian packages the harness itself needs on the host (podman backend).
host_packages=(podman podman-compose debootstrap runc curl iproute2 util-linux)

# install_host_packages: installs what is missing; no network when all present.
install_host_packages() {
  local missing=() p
  for p in "${host_packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [[ ${#missing[@]} -eq 0 ]] && return 0
  [[ $(id -u) -eq 0 ]] || { log "missing ${missing[*]} and not root"; return 1; }
  log "installing ${missing[*]} (Debian)"
  if [[ -z "$(find /var/lib/apt/lists -maxdepth 1 -name '*_Packages' -mmin -1440 2>/dev/null | head -n1)" ]]; then
    run_bounded 600 apt-get update -q >>"$RUN_DIR/apt.log" 2>&1 || return 1
  fi
  DEBIAN_FRONTEND=noninteractive run_bounded 900 \
    apt-get install -y -q --no-install-recommends "${missing[@]}" >>"$RUN_DIR/apt.log" 2>&1
}

# The Debian mirror this machine's apt uses for bookworm (never stored in the project).
apt_mirror() {
  # shellcheck disable=SC2016  # apt's own $(FIELD) placeholders
  apt-get indextargets --format '$(SITE) $(RELEASE) $(IDENTIFIER)' 2>/dev/null |
    awk '!found && $2 == "bookworm" && $3 == "Packages" { print $1; found = 1 }'
}

hash_of() { sha256sum | cut -c1-16; }

# ensure_base_image: sets BASE_IMAGE, BASE_KEY, BASE_STATUS (the rootfs's dpkg status).
ensure_base_image() {
  local mirror arch dir
  mirror=$(apt_mirror)
  [[ -n "$mirror" ]] || { log "no bookworm mirror in this machine's apt sources"; return 1; }
  arch=$(dpkg --print-architecture)
  BASE_KEY=$(printf 'debootstrap minbase bookworm %s %s\n' "$arch" "$mirror" | hash_of)
  dir=$CACHE/base-$BASE_KEY
  BASE_IMAGE=localhost/smc-debian:bookworm-$BASE_KEY
  BASE_STATUS=$dir/dpkg-status
  if [[ ! -f "$dir/rootfs.tar" ]]; then
    log "debootstrap --variant=minbase bookworm ($mirror; once, about 2 min)"
    rm -rf "$dir"
    mkdir -p "$dir"
    if ! run_bounded 1200 debootstrap --variant=minbase --arch="$arch" bookworm "$dir/rootfs" "$mirror" \
      >"$RUN_DIR/debootstrap.log" 2>&1; then
      tail -n 20 "$RUN_DIR/debootstrap.log" >&2
      rm -rf "$dir"
      return 1
    fi
    rm -rf "$dir/rootfs/var/cache/apt/archives/"*.deb "$dir/rootfs/var/lib/apt/lists/"*
    cp "$dir/rootfs/var/lib/dpkg/status" "$dir/dpkg-status.tmp"
    tar --numeric-owner -C "$dir/rootfs" -cf "$dir/rootfs.tar.tmp" .
    rm -rf "$dir/rootfs"
    mv "$dir/dpkg-status.tmp" "$BASE_STATUS"
    mv "$dir/rootfs.tar.tmp" "$dir/rootfs.tar"
  fi
  if ! podman image exists "$BASE_IMAGE"; then
    log "podman import $BASE_IMAGE"
    podman import --message "debootstrap minbase bookworm" "$dir/rootfs.tar" "$BASE_IMAGE" \
      >>"$RUN_DIR/image.log" 2>&1 || return 1
  fi
}

# ensure_debs: sets DEBS_DIR with build/ and runtime/ .deb sets for the offline build.
ensure_debs() {
  local packages="$ROOT/deploy/containers/packages.sh" key stage list
  key=$( { echo "$BASE_KEY"; "$packages" list build; echo --; "$packages" list runtime; } | hash_of)
  DEBS_DIR=$CACHE/debs-$key
  [[ -f "$DEBS_DIR/complete" ]] && return 0
  rm -rf "$DEBS_DIR"
  for stage in build runtime; do
    mapfile -t list < <("$packages" list "$stage")
    mkdir -p "$DEBS_DIR/$stage/partial"
    log "downloading the image's $stage packages (${#list[@]} asked for, with dependencies)"
    local apt_args=(-q -y --download-only --no-install-recommends
      -o "Dir::State::status=$BASE_STATUS" -o "Dir::Cache::archives=$DEBS_DIR/$stage"
      -o Debug::NoLocking=1 install "${list[@]}")
    if ! run_bounded 900 apt-get "${apt_args[@]}" >>"$RUN_DIR/apt.log" 2>&1; then
      # Stale package lists name versions the mirror no longer has.
      run_bounded 600 apt-get update -q >>"$RUN_DIR/apt.log" 2>&1 || true
      run_bounded 900 apt-get "${apt_args[@]}" >>"$RUN_DIR/apt.log" 2>&1 ||
        { tail -n 20 "$RUN_DIR/apt.log" >&2; return 1; }
    fi
    rm -rf "$DEBS_DIR/$stage/partial" "$DEBS_DIR/$stage/lock"
  done
  touch "$DEBS_DIR/complete"
}

# ensure_npm_cache: sets NPM_CACHE, holding the dashboard page's npm packages.
ensure_npm_cache() {
  local web="$ROOT/dashboard/web" key tmp
  NPM_CACHE=$CACHE/npm-none
  mkdir -p "$NPM_CACHE"
  [[ -f "$web/package-lock.json" ]] || return 0
  key=$(cat "$web/package.json" "$web/package-lock.json" | hash_of)
  NPM_CACHE=$CACHE/npm-$key
  [[ -f "$NPM_CACHE/complete" ]] && return 0
  command -v npm >/dev/null || { log "npm is needed on the host to fetch the dashboard page's packages"; return 1; }
  log "npm ci on the host into $NPM_CACHE (the image build is offline)"
  tmp=$(mktemp -d)
  cp "$web/package.json" "$web/package-lock.json" "$tmp/"
  if ! (cd "$tmp" && exec timeout 600 npm ci --cache "$NPM_CACHE" --ignore-scripts --no-audit --no-fund \
    --loglevel=error) >>"$RUN_DIR/npm.log" 2>&1; then
    rm -rf "$tmp"
    tail -n 20 "$RUN_DIR/npm.log" >&2
    return 1
  fi
  rm -rf "$tmp"
  touch "$NPM_CACHE/complete"
}

# The sources the image is built from (the Containerfile's COPY lines).
image_inputs=(deploy/Containerfile deploy/containers deploy/cyclonedds
  CMakeLists.txt CMakePresets.json cmake idl services edge cell dashboard)

# ensure_service_image: sets SMC_IMAGE, building it when its inputs changed.
ensure_service_image() {
  local src key start
  src=$(cd "$ROOT" && find "${image_inputs[@]}" -type f ! -path '*/node_modules/*' -print0 2>/dev/null |
    sort -z | xargs -0 sha256sum | sha256sum)
  key=$(printf '%s\n' "$src" "$BASE_IMAGE" "$DEBS_DIR" | hash_of)
  SMC_IMAGE=localhost/smc:$key
  if podman image exists "$SMC_IMAGE"; then
    log "image $SMC_IMAGE is up to date"
    return 0
  fi
  mkdir -p "$CACHE/ccache"
  log "building $SMC_IMAGE from deploy/Containerfile (offline; cold: ~10 min on 2 cores, seconds once ccache has seen the sources)"
  start=$(date +%s)
  if ! run_bounded 3000 podman build --network=none --layers -f "$ROOT/deploy/Containerfile" \
    --build-arg "BASE=$BASE_IMAGE" \
    --volume "$DEBS_DIR:/var/cache/smc-debs:ro" --volume "$NPM_CACHE:/root/.npm" \
    --volume "$CACHE/ccache:/var/cache/ccache" \
    --label io.smc.ct.image=1 -t "$SMC_IMAGE" "$ROOT" >"$RUN_DIR/image-build.log" 2>&1; then
    tail -n 40 "$RUN_DIR/image-build.log" >&2
    return 1
  fi
  log "image built in $(($(date +%s) - start)) s"
  # Older images of this harness: drop them (their layers stay cached).
  local old
  while read -r old; do
    [[ "$old" == "$SMC_IMAGE" ]] || podman rmi "$old" >/dev/null 2>&1 || true
  done < <(podman images --filter label=io.smc.ct.image=1 --format '{{.Repository}}:{{.Tag}}' | grep '^localhost/smc:')
  # Build stages of earlier images, no longer anyone's parent; the current
  # chain (and so the package layer) is kept as the cache of the next build.
  podman image prune -f --filter until=72h >/dev/null 2>&1 || true
}
