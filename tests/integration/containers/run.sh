#!/usr/bin/env bash
# shellcheck source-path=SCRIPTDIR
# Containerised integration tests of the cell: the cell service, two edges on
# simulated mills and the dashboard, each in its own container on an
# --internal podman network, through five fault scenarios (README.md beside
# this file). Sets up what it needs (podman & co. from Debian, a base image by
# debootstrap, the image from deploy/Containerfile; all cached), prints a
# table of figures and PASS/FAIL per scenario, and ends with the line
# "N passed, N failed". Exit status 0 only when every scenario passed.
#
#   tests/integration/containers/run.sh [options]
#     --backend auto|podman|netns  auto (default): podman, or the network-
#                                  namespace fallback where podman cannot run
#     --only NAME[,NAME...]        some scenarios: full-cell kill-cell cut-link kill-edge pause-cell
#     --bin-dir DIR                netns backend: the host's binaries (default build/release/bin)
#     --timeout SECONDS            hard limit for the whole run (default 2400: a cold image build included)
#     --prepare                    set up (packages, base image, image) and stop
#     --keep                       keep the run folder's logs even when everything passed
#     --insecure                   plain DDS; by default every service runs under DDS
#                                  Security (a PKI made for the run by deploy/security/pki.sh,
#                                  each service on its own identity and permissions)
#
# Needs root (podman, network namespaces). Nothing leaves the machine: the
# containers' network is --internal, the image build runs with --network=none,
# DDS is pinned to each container's eth0 with unicast peers on that network.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$here/../../.." && pwd)

backend=auto
only=""
BIN_DIR=$ROOT/build/release/bin
timeout_s=${SMC_CT_TIMEOUT:-2400}
prepare=0
keep=0
secure=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --backend) backend=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    --bin-dir) BIN_DIR=$(cd "$2" && pwd); shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --prepare) prepare=1; shift ;;
    --keep) keep=1; shift ;;
    --insecure) secure=0; shift ;;
    -h | --help) sed -n '3,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "run.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$backend" in auto | podman | netns) ;; *) echo "run.sh: --backend auto|podman|netns" >&2; exit 2 ;; esac

# shellcheck source=lib/common.sh
source "$here/lib/common.sh"
# shellcheck source=lib/image.sh
source "$here/lib/image.sh"
# shellcheck source=lib/scenarios.sh
source "$here/lib/scenarios.sh"

[[ $(id -u) -eq 0 ]] || die "run as root (podman and network namespaces need it)"

RUN_ID=$(od -An -N3 -tx1 /dev/urandom | tr -d ' \n')
RUN_DIR=${SMC_CT_RUN_DIR:-/tmp/smc-ct-$RUN_ID}
mkdir -p "$RUN_DIR"
export CONTAINERS_CONF=$ROOT/deploy/containers/containers.conf
run_start=$(date +%s)

selected=()
if [[ -n "$only" ]]; then
  IFS=',' read -r -a selected <<<"$only"
  for s in "${selected[@]}"; do
    [[ " ${scenario_names[*]} " == *" $s "* ]] || die "unknown scenario '$s' (${scenario_names[*]})"
  done
else
  selected=("${scenario_names[@]}")
fi

# ------------------------------------------------------ cleanup, watchdog --

# DDS Security: one PKI for the run; the services (uid 10001 in the image)
# read their identity from it, mounted at the same path.
SECURE_PKI=""
if [[ $secure -eq 1 && $prepare -eq 0 ]]; then
  SECURE_PKI=$RUN_DIR/pki
  "$ROOT/deploy/security/pki.sh" init "$SECURE_PKI" --machines mill-1,mill-2 >"$RUN_DIR/pki.log" ||
    die "could not make the run's PKI (log: $RUN_DIR/pki.log)"
  chown -R 10001:10001 "$SECURE_PKI"
fi

backend_ready=0
scenario_pid=""
summary_done=0
declare -A verdict=()

print_summary() {
  [[ $summary_done -eq 1 ]] && return 0
  summary_done=1
  local s f v passed=0 failed=0 row='%-11s %-6s %-8s %-9s %-8s %-16s %s\n'
  echo
  echo "== containerised integration tests, backend: ${BACKEND_NAME:-none}; DDS Security: $([[ -n "$SECURE_PKI" ]] && echo on || echo off)"
  # shellcheck disable=SC2059  # the format is the row above
  printf "$row" scenario result detect recover jobs chatter total
  # shellcheck disable=SC2059
  printf "$row" "" "" "(s)" "(s)" "in>done" "edge>cell/res/ui" "(s)"
  for s in "${selected[@]}"; do
    f=$RUN_DIR/$s/result
    v=${verdict[$s]:-FAIL}
    if [[ "$v" == PASS ]]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
    # shellcheck disable=SC2059
    printf "$row" "$s" "$v" "$(get "$f" detect_s -)" "$(get "$f" recover_s -)" \
      "$(get "$f" jobs_before -)>$(get "$f" jobs_after -)" \
      "$(get "$f" chatter_edges -)>$(get "$f" chatter_cell -)/$(get "$f" chatter_results -)/$(get "$f" chatter_dashboard -)" \
      "$(get "$f" total_s -)"
  done
  for s in "${selected[@]}"; do
    f=$RUN_DIR/$s/result
    [[ -f "$f" ]] || continue
    echo "  $s: fault: $(get "$f" fault -)"
    [[ -n "$(get "$f" detect_by "")" ]] && echo "  $s: detected by $(get "$f" detect_by ""); recovered: $(get "$f" recover_what -)"
    [[ -n "$(get "$f" note "")" ]] && echo "  $s: $(get "$f" note "")"
    [[ -n "$(get "$f" dashboard "")" ]] && echo "  $s: dashboard $(get "$f" dashboard "")"
    [[ "${verdict[$s]:-FAIL}" != PASS ]] && echo "  $s: FAILED: $(get "$f" why "no result (see $RUN_DIR/$s)")"
  done
  echo "== $(($(date +%s) - run_start)) s in all (set-up ${setup_s:-?} s); logs in $RUN_DIR"
  echo "$passed passed, $failed failed"
}

get() { # get FILE KEY DEFAULT: the last KEY=… line of a result file
  local v=""
  [[ -f "$1" ]] && v=$(awk -F= -v k="$2" '$1 == k { sub(/^[^=]*=/, ""); v = $0 } END { print v }' "$1")
  echo "${v:-$3}"
}

cleanup() {
  local rc=$?
  trap - EXIT INT TERM
  set +e  # clean up as much as possible, whatever fails
  if [[ -n "$scenario_pid" ]]; then
    kill -TERM "$scenario_pid" 2>/dev/null
    wait "$scenario_pid" 2>/dev/null
    echo "why=stopped while running (overall timeout or a signal)" >>"$SCENARIO_DIR/result"
  fi
  if [[ -n "$BOUNDED_PID" ]]; then
    kill -TERM "$BOUNDED_PID" 2>/dev/null
    wait "$BOUNDED_PID" 2>/dev/null
  fi
  [[ $backend_ready -eq 1 ]] && be_cleanup
  [[ -n "${watchdog_pid:-}" ]] && kill "$watchdog_pid" 2>/dev/null
  if [[ $prepare -eq 0 ]]; then
    print_summary
    for s in "${selected[@]}"; do [[ "${verdict[$s]:-FAIL}" == PASS ]] || rc=1; done
  fi
  if [[ $rc -eq 0 && $keep -eq 0 && $prepare -eq 0 ]]; then rm -rf "$RUN_DIR"; fi
  exit "$rc"
}
trap cleanup EXIT
trap 'log "interrupted"; exit 130' INT
trap 'log "stopped (timeout or TERM)"; exit 143' TERM

# The whole run is bounded: past the limit the watchdog stops it (the trap
# still removes every container, network and namespace).
(
  trap 'kill "$sleeper" 2>/dev/null; exit 0' TERM
  sleep "$timeout_s" &
  sleeper=$!
  wait "$sleeper"
  log "overall timeout of $timeout_s s reached"
  kill -TERM $$
) >/dev/null &
watchdog_pid=$!

# deploy/compose.yaml describes the same cell; keep it in step with the DDS
# profile (Debian 12's podman-compose cannot run it: see the file).
if python3 -c 'import yaml' 2>/dev/null; then
  python3 "$here/lib/compose_check.py" "$ROOT/deploy/compose.yaml" "$ROOT/deploy/cyclonedds/container.xml" ||
    die "deploy/compose.yaml disagrees with deploy/cyclonedds/container.xml"
else
  log "python3-yaml missing: deploy/compose.yaml not checked"
fi

# ------------------------------------------------------------- back end --

podman_works() {
  install_host_packages || return 1
  timeout 60 podman info >/dev/null 2>&1 || { log "podman info fails"; return 1; }
  ensure_base_image || return 1
  timeout 120 podman run --rm --network none "$BASE_IMAGE" true >>"$RUN_DIR/image.log" 2>&1 ||
    { log "podman cannot run a container here"; return 1; }
}

chosen=$backend
if [[ "$backend" != netns ]]; then
  if podman_works; then
    chosen=podman
  elif [[ "$backend" == podman ]]; then
    die "podman does not work on this machine (logs in $RUN_DIR)"
  else
    log "podman cannot run here: FALLING BACK to one network namespace per service on a bridge"
    chosen=netns
  fi
fi

if [[ "$chosen" == podman ]]; then
  # shellcheck source=lib/podman.sh
  source "$here/lib/podman.sh"
  ensure_debs || die "could not download the image's packages"
  ensure_npm_cache || die "could not fetch the dashboard page's npm packages"
  ensure_service_image || die "the image did not build (log: $RUN_DIR/image-build.log)"
else
  # shellcheck source=lib/netns.sh
  source "$here/lib/netns.sh"
  [[ "$backend" == netns ]] && BACKEND_NAME="netns (as asked: one network namespace per service on a bridge)"
fi
if [[ $prepare -eq 1 ]]; then
  log "prepared (${SMC_IMAGE:-host binaries in $BIN_DIR})"
  exit 0
fi
log "backend: $BACKEND_NAME"
be_init || die "backend set-up failed"
setup_s=$(($(date +%s) - run_start))
backend_ready=1

# ------------------------------------------------------------ scenarios --

SCENARIO_LIMIT=${SMC_CT_SCENARIO_LIMIT:-240}
for s in "${selected[@]}"; do
  SCENARIO=$s
  SCENARIO_DIR=$RUN_DIR/$s
  PARTITION=smc-ct-$RUN_ID-$s
  mkdir -p "$SCENARIO_DIR"
  log "== scenario $s"
  start=$(date +%s)
  (
    set +e
    be_scenario_init || { record status FAIL; record why "scenario set-up failed"; exit 1; }
    "scenario_${s//-/_}"
  ) &
  scenario_pid=$!
  while kill -0 "$scenario_pid" 2>/dev/null; do
    if (($(date +%s) - start > SCENARIO_LIMIT)); then
      log "scenario $s: over its limit of $SCENARIO_LIMIT s; stopping it"
      kill -TERM "$scenario_pid" 2>/dev/null || true
      echo "why=timed out after $SCENARIO_LIMIT s" >>"$SCENARIO_DIR/result"
      break
    fi
    sleep 0.5
  done
  wait "$scenario_pid" 2>/dev/null || true
  scenario_pid=""
  verdict[$s]=$(get "$SCENARIO_DIR/result" status FAIL)
  [[ "$(get "$SCENARIO_DIR/result" why "")" == "timed out"* ]] && verdict[$s]=FAIL
  for svc in cell edge-1 edge-2 dashboard; do be_logs "$svc" >"$SCENARIO_DIR/$svc.log" 2>&1 || true; done
  be_scenario_cleanup
  log "== scenario $s: ${verdict[$s]} ($(($(date +%s) - start)) s)"
done
