# shellcheck shell=bash
# shellcheck disable=SC2034  # BACKEND_NAME: printed by run.sh
# Backend "podman": every service in its own container on one --internal
# podman network (no route out, no DNS, static addresses; each container's
# /etc/hosts names the others). The cell's database is a named volume.
#
# The scenarios use only the be_* functions below; lib/netns.sh implements
# the same ones with network namespaces.
# Needs: SMC_IMAGE, RUN_ID, RUN_DIR, SUBNET_PREFIX (set by be_init), common.sh.

BACKEND_NAME="podman (one container per service, --internal network)"

declare -A SVC_IP=([cell]=10 [edge-1]=11 [edge-2]=12 [dashboard]=20)
PODMAN_NET=""

pm() { timeout 120 podman "$@"; }

# Resources of runs whose harness process is gone (a crash, kill -9).
be_reap_stale() {
  local id pid
  while read -r id pid; do
    [[ -n "$id" ]] || continue
    kill -0 "$pid" 2>/dev/null && continue
    log "removing leftovers of an earlier run ($id)"
    podman ps -aq --filter "label=io.smc.ct=$id" | xargs -r podman rm -f -v -t 0 >/dev/null 2>&1 || true
    podman volume ls -q --filter "label=io.smc.ct=$id" | xargs -r podman volume rm -f >/dev/null 2>&1 || true
    podman network ls -q --filter "label=io.smc.ct=$id" | xargs -r podman network rm -f >/dev/null 2>&1 || true
  done < <(
    {
      podman ps -a --filter label=io.smc.ct --format '{{index .Labels "io.smc.ct"}} {{index .Labels "io.smc.ct.pid"}}'
      podman network ls --filter label=io.smc.ct --format '{{index .Labels "io.smc.ct"}} {{index .Labels "io.smc.ct.pid"}}'
    } 2>/dev/null | sort -u
  )
}

be_init() {
  be_reap_stale
  local third
  for third in $(seq 77 99); do
    PODMAN_NET=smc-ct-$RUN_ID
    if pm network create --internal --subnet "10.213.$third.0/24" \
      --label "io.smc.ct=$RUN_ID" --label "io.smc.ct.pid=$$" "$PODMAN_NET" >/dev/null 2>&1; then
      SUBNET_PREFIX=10.213.$third
      log "network $PODMAN_NET: --internal, 10.213.$third.0/24"
      return 0
    fi
  done
  log "could not create an --internal podman network"
  return 1
}

be_ip() { echo "$SUBNET_PREFIX.${SVC_IP[$1]}"; }
cname() { echo "smc-ct-$RUN_ID-$SCENARIO-$1"; }

# be_start SERVICE: starts the service's container (cell, edge-1, edge-2, dashboard).
be_start() {
  local svc=$1 logdir="$SCENARIO_DIR/$1" args=()
  mkdir -p "$logdir"
  chown 10001:10001 "$logdir"
  args=(run -d --name "$(cname "$svc")" --hostname "$svc"
    --label "io.smc.ct=$RUN_ID" --label "io.smc.ct.pid=$$"
    --network "$PODMAN_NET" --ip "$(be_ip "$svc")"
    --log-driver k8s-file -v "$logdir:/var/log/smc"
    -e "SMC_PARTITION=$PARTITION" -e SMC_DDS_TRACE=/var/log/smc/dds.log -e SMC_LOG_LEVEL=info)
  local peer
  for peer in "${!SVC_IP[@]}"; do args+=(--add-host "$peer:$(be_ip "$peer")"); done
  if [[ -n "${SECURE_PKI:-}" ]]; then
    args+=(-v "$SECURE_PKI:$SECURE_PKI:ro" -e "SMC_DDS_SECURITY=$(security_file "$svc")")
  fi
  case "$svc" in
    cell)
      args+=(-v "$(cname db):/var/lib/smc" -e SMC_CELL_SEED=1 -e "SMC_EDGE_GRACE_MS=$EDGE_GRACE_MS")
      ;;
    edge-*)
      args+=(-e "SMC_MACHINE=mill-${svc#edge-}" -e "SMC_LEASE_MS=$EDGE_LEASE_MS" -e "SMC_SPEEDUP=$SPEEDUP"
        -e SMC_PACED=1 -e SMC_REALTIME=0 -e "SMC_EDGE_RESTART_DELAY_S=$EDGE_RESTART_DELAY_S")
      ;;
    dashboard)
      args+=(-e "SMC_HTTP=$(be_ip dashboard):8080")
      ;;
  esac
  pm "${args[@]}" "$SMC_IMAGE" "${svc%-[0-9]}" >/dev/null
}

# The scenario's own volume and a tool container on it (no network): runs
# smc-cell's offline commands (job submit, list, show) whether or not the
# cell's container is up.
be_scenario_init() {
  pm volume create --label "io.smc.ct=$RUN_ID" "$(cname db)" >/dev/null
  pm run -d --name "$(cname tools)" --label "io.smc.ct=$RUN_ID" --label "io.smc.ct.pid=$$" \
    --network none -v "$(cname db):/var/lib/smc" "$SMC_IMAGE" sleep infinity >/dev/null
  # The cell seeds the database when it starts; the tools may be first.
  pm exec "$(cname tools)" smc-cell db init --db /var/lib/smc/cell.db --seed >/dev/null
}

be_scenario_cleanup() {
  podman ps -aq --filter "label=io.smc.ct=$RUN_ID" --filter "name=smc-ct-$RUN_ID-$SCENARIO-" |
    xargs -r timeout 120 podman rm -f -v -t 0 >/dev/null 2>&1 || true
  podman volume rm -f "$(cname db)" >/dev/null 2>&1 || true
}

be_cleanup() {
  [[ -n "$PODMAN_NET" ]] || return 0
  podman ps -aq --filter "label=io.smc.ct=$RUN_ID" | xargs -r timeout 120 podman rm -f -v -t 0 >/dev/null 2>&1 || true
  podman volume ls -q --filter "label=io.smc.ct=$RUN_ID" | xargs -r podman volume rm -f >/dev/null 2>&1 || true
  podman network rm -f "$PODMAN_NET" >/dev/null 2>&1 || true
  local left
  left=$( {
    podman ps -aq --filter "label=io.smc.ct=$RUN_ID"
    podman volume ls -q --filter "label=io.smc.ct=$RUN_ID"
    podman network ls -q --filter "label=io.smc.ct=$RUN_ID"
  } 2>/dev/null | wc -l)
  [[ "$left" -eq 0 ]] || log "warning: $left containers/volumes/networks of this run could not be removed"
}

# smc-cell's offline commands against the scenario's cell database.
be_cli() { pm exec "$(cname tools)" smc-cell --log-level warn "$@" --db /var/lib/smc/cell.db; }
# A job file shipped in the image (cell/jobs/NAME).
be_job_file() { echo "/usr/share/smc/cell/jobs/$1"; }

be_kill() { pm kill --signal KILL "$(cname "$1")" >/dev/null; }
be_restart() { pm start "$(cname "$1")" >/dev/null; }
be_pause() { pm pause "$(cname "$1")" >/dev/null; }
be_unpause() { pm unpause "$(cname "$1")" >/dev/null; }
be_running() { [[ "$(podman inspect -f '{{.State.Status}}' "$(cname "$1")" 2>/dev/null)" == running ]]; }
be_pid() { podman inspect -f '{{.State.Pid}}' "$(cname "$1")"; }

# be_link SERVICE up|down: the service's network link, from inside its namespace.
be_link() { nsenter -t "$(be_pid "$1")" -n ip link set eth0 "$2"; }

# Service output (every start of it), and its Cyclone DDS discovery trace.
be_logs() { podman logs "$(cname "$1")" 2>&1; }
be_trace() { cat "$SCENARIO_DIR/$1/dds.log" 2>/dev/null || true; }

# be_http SERVICE PATH [curl options]: GET from inside the service's network namespace.
be_http() {
  local svc=$1 path=$2
  shift 2
  nsenter -t "$(be_pid "$svc")" -n curl -sS --max-time 5 "$@" "http://$(be_ip "$svc"):8080$path"
}
