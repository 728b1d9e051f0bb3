# shellcheck shell=bash
# shellcheck disable=SC2034  # BACKEND_NAME: printed by run.sh
# Backend "netns", the fallback where podman cannot run: every service in its
# own network namespace, its eth0 one end of a veth pair whose other end is on
# a bridge of this run. The bridge has no address and nothing routes to or
# from it, so no packet leaves the machine. The services are the host's build
# (BIN_DIR) started through the image's own entry point
# (deploy/containers/entrypoint.sh) with the same container DDS profile; "ip
# netns exec" gives each namespace its own /etc/hosts (/etc/netns/NAME/hosts).
# The cell's database is a folder of the run. pause is SIGSTOP, like podman's
# cgroup freezer.
# Needs: BIN_DIR, ROOT, RUN_ID, RUN_DIR, common.sh.

BACKEND_NAME="netns (FALLBACK: one network namespace per service on a bridge; podman could not run here)"

declare -A SVC_IP=([cell]=10 [edge-1]=11 [edge-2]=12 [dashboard]=20)
NETNS_BRIDGE=""
SUBNET_PREFIX=10.213.77

nsname() { echo "smc-$RUN_ID-$1"; }
be_ip() { echo "$SUBNET_PREFIX.${SVC_IP[$1]}"; }

be_init() {
  local svc ns host n=0
  for p in smc-cell smc-edge; do
    [[ -x "$BIN_DIR/$p" ]] || { log "netns backend: $BIN_DIR/$p is missing (build the project first)"; return 1; }
  done
  NETNS_BRIDGE=smcbr$RUN_ID
  ip link add "$NETNS_BRIDGE" type bridge || return 1
  ip link set "$NETNS_BRIDGE" up
  for svc in "${!SVC_IP[@]}"; do
    n=$((n + 1))
    ns=$(nsname "$svc")
    host=smcv$RUN_ID$n
    ip netns add "$ns"
    ip link add "$host" type veth peer name eth0 netns "$ns"
    ip link set "$host" master "$NETNS_BRIDGE" up
    ip -n "$ns" addr add "$(be_ip "$svc")/24" dev eth0
    ip -n "$ns" link set lo up
    ip -n "$ns" link set eth0 up
    mkdir -p "/etc/netns/$ns"
    {
      echo "127.0.0.1 localhost"
      local peer
      for peer in "${!SVC_IP[@]}"; do echo "$(be_ip "$peer") $peer"; done
    } >"/etc/netns/$ns/hosts"
  done
  log "bridge $NETNS_BRIDGE (no address, no route out), namespaces $(nsname '*'), 10.213.77.0/24"
}

# Every process started, "SERVICE PID" per line (the scenarios run in
# subshells; the run's clean-up reads this file).
pids_file() { echo "$RUN_DIR/netns-pids"; }

be_cleanup() {
  local svc pid
  while read -r svc pid; do
    kill -CONT "$pid" 2>/dev/null || true
    kill -KILL "$pid" 2>/dev/null || true
  done < <(cat "$(pids_file)" 2>/dev/null)
  [[ -n "$NETNS_BRIDGE" ]] || return 0
  for svc in "${!SVC_IP[@]}"; do
    ip netns del "$(nsname "$svc")" 2>/dev/null || true
    rm -rf "/etc/netns/$(nsname "$svc")"
  done
  ip link del "$NETNS_BRIDGE" 2>/dev/null || true
  if [[ "$(ip netns list | grep -c "^smc-$RUN_ID-")" -gt 0 ]] || ip link show "$NETNS_BRIDGE" >/dev/null 2>&1; then
    log "warning: namespaces or the bridge of this run could not be removed"
  fi
}

be_scenario_init() {
  mkdir -p "$SCENARIO_DIR/db"
  be_cli_raw db init --db "$SCENARIO_DIR/db/cell.db" --seed >/dev/null
}

be_scenario_cleanup() {
  local svc pid
  while read -r svc pid; do
    kill -CONT "$pid" 2>/dev/null || true
    kill -KILL "$pid" 2>/dev/null || true
  done < <(grep "^$SCENARIO/" "$(pids_file)" 2>/dev/null)
  sleep 0.2
  # Links a scenario cut come back for the next one.
  for svc in "${!SVC_IP[@]}"; do ip -n "$(nsname "$svc")" link set eth0 up 2>/dev/null || true; done
}

be_cli_raw() { SMC_CELL_DATA="$ROOT/cell" "$BIN_DIR/smc-cell" --log-level warn "$@"; }
be_cli() { be_cli_raw "$@" --db "$SCENARIO_DIR/db/cell.db"; }
be_job_file() { echo "$ROOT/cell/jobs/$1"; }

# be_start SERVICE: the service in its namespace, through the image's entry point.
be_start() {
  local svc=$1 dir="$SCENARIO_DIR/$1" env=()
  mkdir -p "$dir"
  env=(PATH="$BIN_DIR:/usr/sbin:/usr/bin:/sbin:/bin"
    CYCLONEDDS_URI="file://$ROOT/deploy/cyclonedds/container.xml"
    SMC_PARTITION="$PARTITION" SMC_DDS_TRACE="$dir/dds.log" SMC_LOG_LEVEL=info
    SMC_CELL_DATA="$ROOT/cell")
  [[ -z "${SECURE_PKI:-}" ]] || env+=(SMC_DDS_SECURITY="$(security_file "$svc")")
  case "$svc" in
    cell)
      env+=(SMC_CELL_DB="$SCENARIO_DIR/db/cell.db" SMC_CELL_SEED=1 SMC_EDGE_GRACE_MS="$EDGE_GRACE_MS")
      ;;
    edge-*)
      env+=(SMC_MACHINE="mill-${svc#edge-}" SMC_LEASE_MS="$EDGE_LEASE_MS" SMC_SPEEDUP="$SPEEDUP"
        SMC_PACED=1 SMC_REALTIME=0 SMC_MILL_MODEL="$ROOT/cell/models/paper_face_mill.textproto"
        SMC_EDGE_RESTART_DELAY_S="$EDGE_RESTART_DELAY_S" SMC_STATE_DIR="$dir")
      ;;
    dashboard)
      [[ -x "$BIN_DIR/smc-dashboard" ]] || { log "netns backend: no smc-dashboard in $BIN_DIR"; return 1; }
      env+=(SMC_HTTP="$(be_ip dashboard):8080")
      ;;
  esac
  ip netns exec "$(nsname "$svc")" env -i "${env[@]}" \
    "$ROOT/deploy/containers/entrypoint.sh" "${svc%-[0-9]}" >>"$dir/service.log" 2>&1 &
  echo "$SCENARIO/$svc $!" >>"$(pids_file)"
}

# The service's current process (the last one started).
be_pid() { awk -v k="$SCENARIO/$1" '$1 == k { p = $2 } END { if (p) print p; else exit 1 }' "$(pids_file)"; }
be_kill() {
  local pid
  pid=$(be_pid "$1")
  kill -KILL "$pid"
  wait "$pid" 2>/dev/null || true
}
be_restart() { be_start "$1"; }
be_pause() { kill -STOP "$(be_pid "$1")"; }
be_unpause() { kill -CONT "$(be_pid "$1")"; }
be_running() {
  local pid
  pid=$(be_pid "$1" 2>/dev/null) || return 1
  kill -0 "$pid" 2>/dev/null
}
be_link() { nsenter -t "$(be_pid "$1")" -n ip link set eth0 "$2"; }
be_logs() { cat "$SCENARIO_DIR/$1/service.log" 2>/dev/null || true; }
be_trace() { cat "$SCENARIO_DIR/$1/dds.log" 2>/dev/null || true; }
be_http() {
  local svc=$1 path=$2
  shift 2
  nsenter -t "$(be_pid "$svc")" -n curl -sS --max-time 5 "$@" "http://$(be_ip "$svc"):8080$path"
}
