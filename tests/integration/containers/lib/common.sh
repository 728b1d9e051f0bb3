# shellcheck shell=bash
# Shared helpers of the containerised integration tests: logging, clocks,
# bounded waits, log parsing. Sourced by run.sh; no side effects.

now() { date +%s.%N; }

# elapsed A B: B - A in seconds with two decimals ("-" when either is empty).
elapsed() {
  if [[ -z "${1:-}" || -z "${2:-}" ]]; then
    echo "-"
    return
  fi
  awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'
}

# A spdlog timestamp (2026-01-02T03:04:05.678, UTC in the containers) or a
# job event's (…Z) as epoch seconds.
to_epoch() {
  local t=${1%Z}
  date -u -d "${t/T/ } UTC" +%s.%N
}

# run_bounded SECONDS COMMAND...: COMMAND with a time limit, in the
# background so that a signal to the harness is handled at once (its trap
# stops BOUNDED_PID, and timeout passes the signal on to COMMAND).
BOUNDED_PID=""
run_bounded() {
  local limit=$1 rc=0
  shift
  timeout "$limit" "$@" &
  BOUNDED_PID=$!
  wait "$BOUNDED_PID" || rc=$?
  BOUNDED_PID=""
  return "$rc"
}

log() { printf '%s %s\n' "$(date -u +%H:%M:%S)" "$*" >&2; }
die() {
  log "error: $*"
  exit 1
}

# wait_for SECONDS DESCRIPTION COMMAND...: runs COMMAND every 0.2 s until it
# succeeds; fails (returns 1, with a message) after SECONDS.
wait_for() {
  local limit=$1 what=$2
  shift 2
  local deadline
  deadline=$(awk -v n="$(date +%s.%N)" -v l="$limit" 'BEGIN { printf "%.3f", n + l }')
  while true; do
    if "$@"; then return 0; fi
    if awk -v n="$(date +%s.%N)" -v d="$deadline" 'BEGIN { exit !(n > d) }'; then
      log "timed out after ${limit} s waiting for: $what"
      return 1
    fi
    sleep 0.2
  done
}

# Readers of a pipe below always read it to the end: stopping early would
# kill the writer with SIGPIPE, which pipefail turns into a failure.

# first_line_after EPOCH PATTERN: the epoch of the first spdlog line on stdin
# that matches PATTERN (an ERE) and is stamped at or after EPOCH.
first_line_after() {
  local since=$1 pattern=$2 line ts
  while IFS= read -r line; do
    [[ "$line" =~ $pattern ]] || continue
    ts=$(line_epoch "$line") || continue
    if awk -v a="$ts" -v b="$since" 'BEGIN { exit !(a >= b) }'; then
      echo "$ts"
      cat >/dev/null
      return 0
    fi
  done
  return 1
}

# line_epoch LINE: the epoch of a spdlog line (2026-…T…  level [name] text).
line_epoch() {
  local stamp=${1%% *}
  [[ "$stamp" =~ ^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:.]+$ ]] || return 1
  to_epoch "$stamp"
}

# Cyclone DDS discovery trace (SMC_DDS_TRACE) of one process, on stdin.
#   dds_guids_of PROCESS: GUIDs of the participants of that process name
#   dds_lost_after EPOCH GUIDS...: epoch of the first lease expiry of one of them
#   dds_found_after EPOCH GUIDS-OR-PROCESS: epoch of the first discovery (SPDP NEW)
dds_guids_of() {
  grep -F 'NEW' | grep -F "\"__ProcessName\":\"$1\"" |
    sed -n 's/.*SPDP ST[0-9]* \([0-9a-f:]*\) .*/\1/p' | sort -u
}
dds_lost_after() {
  local since=$1
  shift
  local re
  re=$(IFS='|'; echo "$*")
  [[ -n "$re" ]] || return 1
  awk -v since="$since" -v re="guid (${re//:/\\:}) " '
    !found && /lease expired/ && $0 ~ re && $1 + 0 >= since { print $1; found = 1 }
    END { exit !found }'
}
dds_found_after() {
  local since=$1 process=$2
  awk -v since="$since" -v p="\"__ProcessName\":\"$process\"" '
    !found && /SPDP ST[0-9]* .* NEW / && index($0, p) && $1 + 0 >= since { print $1; found = 1 }
    END { exit !found }'
}

# max_of / min_of: the largest / smallest of the numbers given ("" if none).
max_of() { printf '%s\n' "$@" | awk 'NF { if (!n++ || $1 > m) m = $1 } END { if (n) print m }'; }
min_of() { printf '%s\n' "$@" | awk 'NF { if (!n++ || $1 < m) m = $1 } END { if (n) print m }'; }

# security_file SERVICE: the service's DDS Security fragment (pki.sh's
# security.xml of its identity), or nothing when the run is insecure.
security_file() {
  [[ -n "${SECURE_PKI:-}" ]] || return 0
  case "$1" in
    edge-*) echo "$SECURE_PKI/edge-mill-${1#edge-}/security.xml" ;;
    *) echo "$SECURE_PKI/$1/security.xml" ;;
  esac
}
