#!/usr/bin/env bash
# Entry point of the smc image: runs one of the cell's services with the
# container's Cyclone DDS profile, or any command.
#
#   cell        smc-cell serve on $SMC_CELL_DB (the volume); the database is
#               created or migrated first, and seeded when SMC_CELL_SEED=1
#   edge        smc-edge run for $SMC_MACHINE on the simulated mill
#   dashboard   smc-dashboard on $SMC_HTTP
#   help        this text
#   anything else runs as a command, e.g. smc-cell job submit FILE, smc-cell job list
#
# Arguments after the service name are passed to it. Environment [default]:
#   SMC_PARTITION [cell]   DDS partition of the cell     SMC_DOMAIN [0]  DDS domain
#   SMC_LOG_LEVEL, SMC_LOG_FORMAT                       the services' logging
#   SMC_DDS_PEERS          more Cyclone DDS peers (names or addresses, space-separated)
#   SMC_DDS_TRACE          file for Cyclone DDS discovery tracing (peers found and lost)
#   SMC_DDS_SECURITY       DDS Security: this participant's security.xml from
#                          deploy/security/pki.sh (its identity, permissions and the
#                          cell's CAs), added to the profile; readable by this user
#   CYCLONEDDS_URI         [file:///etc/smc/cyclonedds/container.xml]
#   cell:      SMC_CELL_DB [/var/lib/smc/cell.db]  SMC_CELL_SEED [0]
#              SMC_EDGE_GRACE_MS [6000]  SMC_MAX_ATTEMPTS [3]
#   edge:      SMC_MACHINE (required)  SMC_LEASE_MS [2000]  SMC_SPEEDUP [1]
#              SMC_EDGE_RESTART_DELAY_S [10] (a restart waits this long: more
#              than the lease + the cell's grace; see below)  SMC_STATE_DIR [/tmp]
#              SMC_PACED [0]  SMC_REALTIME [1] (SCHED_FIFO and mlockall need
#              CAP_SYS_NICE, CAP_IPC_LOCK and a memlock limit; without them the
#              edge says so and runs without)
#              SMC_MILL_MODEL [/usr/share/smc/cell/models/paper_face_mill.textproto]
#                the simulated mill's own "true" model; e.g.
#                .../paper_face_mill_mismatched.textproto for a mill that
#                differs from the cell's database
#   dashboard: SMC_HTTP [0.0.0.0:8080]  SMC_TOKEN_FILE (operator tokens; read-only without)
#              SMC_CELL_DB (the cell's database, for job history pages; none without)
set -euo pipefail

service=${1:-help}
[[ $# -gt 0 ]] && shift

# Cyclone DDS: the profile, then fragments for extra peers and tracing.
uri=${CYCLONEDDS_URI:-file:///etc/smc/cyclonedds/container.xml}
if [[ -n "${SMC_DDS_PEERS:-}" ]]; then
  peers=""
  for p in ${SMC_DDS_PEERS//,/ }; do
    [[ "$p" =~ ^[A-Za-z0-9._:-]+$ ]] || { echo "smc-entrypoint: bad peer '$p' in SMC_DDS_PEERS" >&2; exit 2; }
    peers+="<Peer address=\"$p\"/>"
  done
  uri+=",<Discovery><Peers>$peers</Peers></Discovery>"
fi
if [[ -n "${SMC_DDS_SECURITY:-}" ]]; then
  if [[ ! -r "$SMC_DDS_SECURITY" ]]; then
    echo "smc-entrypoint: SMC_DDS_SECURITY: cannot read '$SMC_DDS_SECURITY' as uid $(id -u)" \
      "(a participant's security.xml from deploy/security/pki.sh, mounted with its files)" >&2
    exit 2
  fi
  uri+=",$(tr -d '\n' <"$SMC_DDS_SECURITY")"
fi
if [[ -n "${SMC_DDS_TRACE:-}" ]]; then
  uri+=",<Tracing><Category>discovery</Category><OutputFile>$SMC_DDS_TRACE</OutputFile></Tracing>"
fi
export CYCLONEDDS_URI=$uri

partition=${SMC_PARTITION:-cell}
domain=${SMC_DOMAIN:-0}

case "$service" in
  cell)
    db=${SMC_CELL_DB:-/var/lib/smc/cell.db}
    init=(smc-cell db init --db "$db")
    [[ "${SMC_CELL_SEED:-0}" == 1 ]] && init+=(--seed)
    "${init[@]}" >/dev/null
    exec smc-cell serve --db "$db" --domain "$domain" --partition "$partition" \
      --edge-grace-ms "${SMC_EDGE_GRACE_MS:-6000}" --max-attempts "${SMC_MAX_ATTEMPTS:-3}" "$@"
    ;;
  edge)
    [[ -n "${SMC_MACHINE:-}" ]] || { echo "smc-entrypoint: edge needs SMC_MACHINE (e.g. mill-1)" >&2; exit 2; }
    # A restarted edge (a crash, a restart policy) would be handed the
    # assignment it was running and start that job over from the beginning,
    # unknown to the cell. Waiting out the cell's lease + grace first lets the
    # cell interrupt the job and withdraw the assignment, as its policy says
    # (cell/README.md, "Edge lost"). The marker lives in the container's own
    # file system, so only a restart of the same container waits.
    marker=${SMC_STATE_DIR:-/tmp}/smc-edge-started-$SMC_MACHINE
    if [[ -e "$marker" ]]; then
      delay=${SMC_EDGE_RESTART_DELAY_S:-10}
      echo "smc-entrypoint: $SMC_MACHINE restarted; waiting ${delay} s so that the cell withdraws its job" >&2
      sleep "$delay"
    fi
    touch "$marker"
    args=(run --machine "$SMC_MACHINE" --domain "$domain" --partition "$partition"
          --lease-ms "${SMC_LEASE_MS:-2000}" --speedup "${SMC_SPEEDUP:-1}"
          --mill-model "${SMC_MILL_MODEL:-/usr/share/smc/cell/models/paper_face_mill.textproto}")
    [[ "${SMC_PACED:-0}" == 1 ]] && args+=(--paced)
    [[ "${SMC_REALTIME:-1}" == 0 ]] && args+=(--no-realtime)
    exec smc-edge "${args[@]}" "$@"
    ;;
  dashboard)
    args=(--http "${SMC_HTTP:-0.0.0.0:8080}" --domain "$domain" --partition "$partition")
    [[ -n "${SMC_TOKEN_FILE:-}" ]] && args+=(--token-file "$SMC_TOKEN_FILE")
    [[ -n "${SMC_CELL_DB:-}" ]] && args+=(--cell-db "$SMC_CELL_DB")
    exec smc-dashboard "${args[@]}" "$@"
    ;;
  help | -h | --help)
    sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
    ;;
  *)
    exec "$service" "$@"
    ;;
esac
