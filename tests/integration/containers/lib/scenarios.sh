# shellcheck shell=bash
# shellcheck disable=SC2034  # SPEEDUP, scenario_names, …: used by run.sh and the backends
# The five scenarios. Each runs in its own subshell with its own containers
# (or namespaces), database, DDS partition and folder ($SCENARIO_DIR), and
# writes its figures and verdict to $SCENARIO_DIR/result (key=value lines).
# They use only the backend's be_* functions and the product's own commands.
#
# Figures, for every scenario:
#   detect   fault -> the first component that noticed it (named in "by")
#   recover  end of the fault (restart, link up, unpause; for a killed edge
#            the kill itself) -> the cell working normally again (named in "what")
#   jobs     accepted by the cell (in its database) before the end of the fault
#            -> done after it, each attempt run exactly once
#   chatter  events the edges detected (their own logs) -> events the cell
#            received (distinct) / in the jobs' results / on the dashboard; a
#            result holds the events of the attempt that finished, so it is
#            compared with those (they differ only when an attempt was interrupted)

# Tunables (seconds unless named _MS); the README's figures use these.
SPEEDUP=${SMC_CT_SPEEDUP:-8}          # machine seconds per wall second: jobs take ~5 s
EDGE_LEASE_MS=${SMC_CT_EDGE_LEASE_MS:-1000}
EDGE_GRACE_MS=${SMC_CT_EDGE_GRACE_MS:-6000}
# A restarted edge waits for the cell to withdraw its job (entrypoint.sh).
EDGE_RESTART_DELAY_S=$(((EDGE_LEASE_MS + EDGE_GRACE_MS) / 1000 + 2))
CELL_DOWN_S=${SMC_CT_CELL_DOWN_S:-4}  # kill-cell: down longer than the DDS lease (3 s)
LINK_DOWN_S=${SMC_CT_LINK_DOWN_S:-5}  # cut-link: longer than both leases, shorter than the grace
PAUSE_S=${SMC_CT_PAUSE_S:-5}          # pause-cell: longer than the DDS lease

scenario_names=(full-cell kill-cell cut-link kill-edge pause-cell)

# ---------------------------------------------------------------- helpers --

FAILURES=()
fail() {
  FAILURES+=("$*")
  log "  FAIL: $*"
}
check() {
  local what=$1
  shift
  if "$@"; then log "  ok: $what"; else fail "$what"; fi
}
eq() { [[ "$1" == "$2" ]]; }
ge() { [[ "$1" =~ ^[0-9]+$ && "$1" -ge "$2" ]]; }
# within SECONDS LIMIT: a measured time exists and is at most LIMIT.
within() { [[ "$1" =~ ^[0-9.]+$ ]] && awk -v a="$1" -v b="$2" 'BEGIN { exit !(a <= b) }'; }

# The stated times (s), with 1 s for polling and scheduling: the DDS
# participant lease of deploy/cyclonedds/container.xml, the edges' liveliness
# lease, and that lease plus the cell's grace before it interrupts a job.
DDS_LEASE_S=3
LEASE_LIMIT_S=$(awk -v l="$EDGE_LEASE_MS" 'BEGIN { print l / 1000 + 1 }')
GRACE_LIMIT_S=$(awk -v l="$EDGE_LEASE_MS" -v g="$EDGE_GRACE_MS" 'BEGIN { print (l + g) / 1000 + 1 }')

record() { echo "$1=$2" >>"$SCENARIO_DIR/result"; }

cell_log_has() { be_logs cell | grep -cE "$1" >/dev/null; }
cell_sees_mills() { cell_log_has "edge mill-1 is alive" && cell_log_has "edge mill-2 is alive"; }
dashboard_up() { be_http dashboard /api/health 2>/dev/null | grep -c '"ok":true' >/dev/null; }

# The cell, two edges and the dashboard, started in order; ready when the
# cell has seen both mills alive and the dashboard answers.
start_cell() {
  be_start cell
  wait_for 30 "the cell service to start" cell_log_has "cell: database" || return 1
  be_start edge-1
  be_start edge-2
  be_start dashboard
  wait_for 30 "the cell to see both mills" cell_sees_mills || return 1
  wait_for 30 "the dashboard to answer" dashboard_up || return 1
}

# submit FILE: submits a job from cell/jobs and prints its id.
submit() {
  local out
  out=$(be_cli job submit "$(be_job_file "$1")") || return 1
  echo "${out%% *}"
}

# jobs: "ID STATE PART MACHINE VARIANT ATTEMPT" per job (VARIANT as SMC_I,
# SMC_II or -), from smc-cell job list's columns (found by their headings).
jobs() {
  be_cli job list | awk '
    NR == 1 { v = index($0, "VARIANT"); a = index($0, "ATTEMPT"); next }
    $1 ~ /^job-/ {
      variant = substr($0, v, a - v); gsub(/^ +| +$/, "", variant); gsub(/ /, "_", variant)
      print $1, $2, $3, $4, variant, substr($0, a) + 0
    }'
}
job_field() { jobs | awk -v id="$1" -v f="$2" '$1 == id { print $f }'; }
job_state() { job_field "$1" 2; }
job_machine() { job_field "$1" 4; }
job_variant() { job_field "$1" 5; }
job_attempt() { job_field "$1" 6; }

# all_in STATE IDS...: every job is in one of the states (a|b|…).
all_in() {
  local states=$1 id table
  shift
  table=$(jobs) || return 1
  for id in "$@"; do
    awk -v id="$id" -v re="^($states)$" '$1 == id && $2 ~ re { ok = 1 } END { exit !ok }' <<<"$table" || return 1
  done
}
wait_jobs() {
  local limit=$1 states=$2
  shift 2
  wait_for "$limit" "jobs $* to be $states" all_in "$states" "$@"
}

# Job events (smc-cell job show): "TIME FROM -> TO reason".
job_events() { be_cli job show "$1" | awk '/^  events/ { on = 1; next } on && NF >= 5 { $1 = ""; print }'; }
count_to() { job_events "$1" | awk -v s="$2" '$3 == "->" && $4 == s { n++ } END { print n + 0 }'; }
job_interrupted() { [[ "$(count_to "$1" interrupted)" -ge 1 ]]; }
# time_to ID STATE [N]: epoch of the N-th (default 1st) transition to STATE.
time_to() {
  local t
  t=$(job_events "$1" | awk -v s="$2" -v n="${3:-1}" '$3 == "->" && $4 == s && ++k == n { print $1 }')
  [[ -n "$t" ]] && to_epoch "$t"
}
job_result_line() { be_cli job show "$1" | awk '!done && $1 == "result" { $1 = ""; print; done = 1 }'; }
job_chatter() { job_result_line "$1" | sed -n 's/.* \([0-9][0-9]*\) chatter events.*/\1/p'; }

# first_cell_line EPOCH REGEX: epoch of the cell's first matching log line at or after EPOCH.
first_cell_line() { be_logs cell | first_line_after "$1" "$2"; }

# Chatter events detected by the edges: one "rewrote the program" per event.
edge_chatter() {
  local n=0 svc k
  for svc in edge-1 edge-2; do
    # A chatter suppressed: a pass added (SMC II), or the spindle moved (SMC II+).
    k=$(be_logs "$svc" | grep -cE "chatter suppressor rewrote|spindle speed changed to" || true)
    n=$((n + k))
  done
  echo "$n"
}
# Chatter events the cell received: distinct events, across restarts of the
# cell (a restarted cell is sent the events again; each run counts them once).
cell_chatter() {
  be_logs cell | awk '
    / cell: database / { run++ }
    / chatter \((automatic|operator)\) at / { sub(/^[^ ]+ /, ""); n[$0 SUBSEP run]++; key[$0] = 1 }
    END {
      total = 0
      for (k in key) { best = 0; for (r = 0; r <= run; r++) if (n[k SUBSEP r] > best) best = n[k SUBSEP r]; total += best }
      print total
    }'
}
results_chatter() {
  local n=0 id c
  for id in "$@"; do
    c=$(job_chatter "$id")
    n=$((n + ${c:-0}))
  done
  echo "$n"
}
# Chatter events of the jobs' last attempts, as the cell received them (its
# log lines for the job from the attempt's start on, each event once): what
# the jobs' results must hold, since a result describes the run that finished.
last_attempt_chatter() {
  local n=0 id since k log
  log=$(be_logs cell)
  for id in "$@"; do
    since=$(time_to "$id" running "$(count_to "$id" running)") || continue
    k=$(awk -v id="$id" '/ chatter \((automatic|operator)\) at / && index($0, " in job " id ",")' <<<"$log" |
      while IFS= read -r line; do
        t=$(line_epoch "$line") && awk -v a="$t" -v b="$since" 'BEGIN { exit !(a >= b) }' && echo "${line#* }"
      done | sort -u | wc -l)
    n=$((n + k))
  done
  echo "$n"
}
# The dashboard's mills (GET /api/mills): "ID ONLINE CHATTER_EVENTS" per mill.
dashboard_mills() {
  be_http dashboard /api/mills 2>/dev/null | python3 -c '
import json, sys
for m in json.load(sys.stdin):
    print(m["machine_id"], str(m["online"]).lower(), m["chatter_events"])'
}
dashboard_chatter() { dashboard_mills | awk '{ n += $3 } END { print n + 0 }'; }

# edge_starts ID: how many times an edge started cutting the job (its logs:
# a job start is "paced simulation…" or "real-time set-up…", then "running job ID").
edge_starts() {
  local svc
  for svc in edge-1 edge-2; do be_logs "$svc"; done | awk -v id="$1" '
    /: (paced simulation at|real-time set-up:)/ { started = 1; next }
    started && / running job / { if ($NF == id) n++; started = 0 }
    END { print n + 0 }'
}

# finish IDS...: the counts every scenario reports, and its verdict.
finish() {
  local ids=("$@") done_n=0 id e c r d l m
  for id in "${ids[@]}"; do
    [[ "$(job_state "$id")" == "done" ]] && done_n=$((done_n + 1))
    # The cell's record and the machines agree: every start of a cut is an attempt the cell knows.
    check "$id: cuts started by the edges = runs the cell recorded" eq "$(edge_starts "$id")" "$(count_to "$id" running)"
  done
  # Evidence for the chatter counts: the dashboard's event lists per mill.
  for m in mill-1 mill-2; do
    be_http dashboard "/api/mills/$m/events" >"$SCENARIO_DIR/dashboard-chatter-$m.json" 2>/dev/null || true
  done
  e=$(edge_chatter)
  c=$(cell_chatter)
  r=$(results_chatter "${ids[@]}")
  d=$(dashboard_chatter)
  l=$(last_attempt_chatter "${ids[@]}")
  record jobs_before "${#ids[@]}"
  record jobs_after "$done_n"
  record chatter_edges "$e"
  record chatter_cell "$c"
  record chatter_results "$r"
  record chatter_dashboard "$d"
  check "jobs accepted = jobs done (${#ids[@]} = $done_n)" eq "${#ids[@]}" "$done_n"
  check "chatter: edges = cell = dashboard ($e = $c = $d)" eq "$e $e" "$c $d"
  check "chatter in the job results = events of the runs that finished ($r = $l)" eq "$r" "$l"
  check "the edges detected chatter at all ($e)" ge "$e" 1
  if [[ ${#FAILURES[@]} -eq 0 ]]; then
    record status PASS
  else
    record status FAIL
    record why "$(IFS=';'; echo "${FAILURES[*]}")"
  fi
}

# Each attempt ran exactly once: one "running" per attempt, the attempt expected.
ran_once() {
  local id=$1 attempts=$2
  check "$id ran $attempts time(s), attempt $attempts" eq "$(count_to "$id" running) $(job_attempt "$id")" "$attempts $attempts"
}

# ---------------------------------------------------------- scenarios --

# 1. A full cell: both demo jobs complete with the expected SMC; the
#    dashboard serves live data.
scenario_full_cell() {
  record fault "none"
  start_cell || { fail "the cell did not come up"; finish; return; }
  local tl js t0 sse mills
  t0=$(now)
  tl=$(submit transfer_line.textproto)
  js=$(submit job_shop.json)
  wait_jobs 30 running "$tl" "$js" || fail "jobs not running"
  # Live data: the dashboard's stream for 3 s while the mills cut.
  sse=$(be_http dashboard /api/stream -N --max-time 3 2>/dev/null || true)
  mills=$(dashboard_mills || true)
  echo "$mills" >"$SCENARIO_DIR/dashboard-mills.txt"
  wait_jobs 90 "done" "$tl" "$js" || fail "jobs not done"
  record total_s "$(elapsed "$t0" "$(now)")"
  local summaries progress
  summaries=$(grep -c '^event: summary' <<<"$sse" || true)
  progress=$(grep -c '^event: progress' <<<"$sse" || true)
  record dashboard "stream: $summaries force summaries, $progress progress events in 3 s"
  check "dashboard streams force summaries ($summaries in 3 s)" ge "$summaries" 20
  check "dashboard streams job progress ($progress in 3 s)" ge "$progress" 1
  check "dashboard lists both mills online" eq "$(awk '$2 == "true"' <<<"$mills" | wc -l)" 2
  check "transfer-line job got SMC I" eq "$(job_variant "$tl")" SMC_I
  check "job-shop job got SMC II" eq "$(job_variant "$js")" SMC_II
  ran_once "$tl" 1
  ran_once "$js" 1
  check "job-shop job chattered and was suppressed ($(job_chatter "$js") events)" ge "$(job_chatter "$js")" 1
  finish "$tl" "$js"
}

# 2. Kill the cell's container mid-job (SIGKILL), accept a job while it is
#    down, restart it: nothing accepted is lost, nothing runs twice.
scenario_kill_cell() {
  record fault "SIGKILL the cell mid-job (podman kill; netns: kill -9), a job submitted while down, start again after ${CELL_DOWN_S} s"
  start_cell || { fail "the cell did not come up"; finish; return; }
  local tl js late t_fault t_restart guids lost=() t alive=() m
  tl=$(submit transfer_line.textproto)
  js=$(submit job_shop.json)
  wait_jobs 30 running "$tl" "$js" || fail "jobs not running"
  guids=$(be_trace edge-1 | dds_guids_of smc-cell)
  t_fault=$(now)
  be_kill cell
  late=$(submit job_shop.json) || fail "a job submitted while the cell is down was refused"
  sleep "$CELL_DOWN_S"
  t_restart=$(now)
  be_restart cell
  wait_jobs 120 "done" "$tl" "$js" "$late" || fail "jobs not done after the restart"
  for m in edge-1 edge-2; do
    # shellcheck disable=SC2086
    t=$(be_trace "$m" | dds_lost_after "$t_fault" $guids) && lost+=("$t")
  done
  record detect_s "$(elapsed "$t_fault" "$(min_of "${lost[@]}")")"
  record detect_by "edges' DDS (cell's lease expired)"
  check "the edges dropped the dead cell within the DDS lease (${DDS_LEASE_S} s)" \
    within "$(elapsed "$t_fault" "$(min_of "${lost[@]}")")" $((DDS_LEASE_S + 1))
  for m in 1 2; do
    t=$(first_cell_line "$t_restart" "edge mill-$m is alive") && alive+=("$t")
  done
  check "the restarted cell saw both mills again" eq "${#alive[@]}" 2
  record recover_s "$(elapsed "$t_restart" "$(max_of "${alive[@]}")")"
  record recover_what "restart -> new cell sees both mills"
  record total_s "$(elapsed "$t_fault" "$(now)")"
  check "the cell resumed the jobs it had out" cell_log_has "resuming as (running|assigned)"
  ran_once "$tl" 1
  ran_once "$js" 1
  ran_once "$late" 1
  finish "$tl" "$js" "$late"
}

# 3. Cut the link of the edge cutting the job-shop part (ip link set eth0
#    down inside its namespace) just after its first chatter event, for
#    LINK_DOWN_S, then restore it: the edge goes on cutting (and finishes the
#    job while cut off, at 8x), the cell notices within the liveliness lease,
#    and both reconcile when the link returns: the result arrives, and the
#    chatter event sent before the cut is delivered again (transient-local)
#    and must be counted once everywhere.
scenario_cut_link() {
  record fault "ip link set eth0 down (nsenter -n) on the edge cutting the SMC II job, after its first chatter; up after ${LINK_DOWN_S} s"
  start_cell || { fail "the cell did not come up"; finish; return; }
  local tl js mill svc t_down t_up t_lost t_alive t_done elog
  tl=$(submit transfer_line.textproto)
  js=$(submit job_shop.json)
  wait_jobs 30 running "$js" || fail "job not running"
  wait_for 20 "the job's first chatter event" cell_log_has "chatter .* in job $js," || fail "no chatter"
  mill=$(job_machine "$js")
  svc=edge-${mill#mill-}
  t_down=$(now)
  be_link "$svc" down
  sleep "$LINK_DOWN_S"
  t_up=$(now)
  be_link "$svc" up
  wait_jobs 90 "done" "$tl" "$js" || fail "jobs not done after the link returned"
  t_lost=$(first_cell_line "$t_down" "edge $mill lost \(liveliness\)") || fail "the cell never noticed $mill's link cut"
  t_alive=$(first_cell_line "$t_up" "edge $mill is alive") || fail "the cell never saw $mill again"
  record detect_s "$(elapsed "$t_down" "$t_lost")"
  record detect_by "cell (liveliness of $mill lost)"
  check "the cell noticed within the lease (${EDGE_LEASE_MS} ms)" within "$(elapsed "$t_down" "$t_lost")" "$LEASE_LIMIT_S"
  record recover_s "$(elapsed "$t_up" "$t_alive")"
  record recover_what "link up -> cell sees $mill alive"
  record total_s "$(elapsed "$t_down" "$(now)")"
  elog=$(be_logs "$svc")
  t_done=$(first_line_after "$t_down" "job $js done" <<<"$elog" || true)
  local when="after"
  [[ -n "$t_done" ]] && awk -v a="$t_done" -v b="$t_up" 'BEGIN { exit !(a < b) }' && when="while cut off,"
  record note "the edge finished the job $when $(elapsed "$t_down" "$t_done") s after the cut (link up after ${LINK_DOWN_S} s)"
  check "the edge kept cutting: no fault, no feed hold" eq "$(grep -cE 'fault hold|feed hold' <<<"$elog" || true)" 0
  check "job-shop job completed all its passes" eq "$(job_result_line "$js" | awk '{ print $1 }')" "completed,"
  check "no job interrupted by the cut" eq "$(count_to "$js" interrupted)$(count_to "$tl" interrupted)" "00"
  ran_once "$tl" 1
  ran_once "$js" 1
  finish "$tl" "$js"
}

# 4. Kill the container of the edge cutting the job-shop part, and start it
#    again at once (as a restart policy would): the job is interrupted and
#    re-queued (cell/README.md), then done by the next idle mill; the
#    restarted edge does not start the old attempt over.
scenario_kill_edge() {
  record fault "SIGKILL the edge cutting the SMC II job, after its first chatter; started again at once"
  start_cell || { fail "the cell did not come up"; finish; return; }
  local tl js mill svc t_kill t_lost t_int t_req t_run2
  tl=$(submit transfer_line.textproto)
  js=$(submit job_shop.json)
  wait_jobs 30 running "$js" || fail "job not running"
  # Killed after its first chatter event: that attempt's events must arrive too.
  wait_for 20 "the job's first chatter event" cell_log_has "chatter .* in job $js," || fail "no chatter"
  mill=$(job_machine "$js")
  svc=edge-${mill#mill-}
  t_kill=$(now)
  be_kill "$svc"
  be_restart "$svc"
  wait_for 30 "the job to be interrupted" job_interrupted "$js" || fail "job not interrupted"
  wait_jobs 120 "done" "$tl" "$js" || fail "jobs not done"
  t_lost=$(first_cell_line "$t_kill" "edge $mill lost \(liveliness\)") || fail "the cell never noticed $mill's death"
  t_int=$(time_to "$js" interrupted)
  t_req=$(time_to "$js" queued 2)
  t_run2=$(time_to "$js" running 2)
  record detect_s "$(elapsed "$t_kill" "$t_lost")"
  record detect_by "cell (liveliness of $mill lost)"
  check "the cell noticed within the lease (${EDGE_LEASE_MS} ms)" within "$(elapsed "$t_kill" "$t_lost")" "$LEASE_LIMIT_S"
  check "the job was interrupted within lease + grace" within "$(elapsed "$t_kill" "$t_int")" "$GRACE_LIMIT_S"
  record recover_s "$(elapsed "$t_kill" "$t_run2")"
  record recover_what "kill -> job running again (attempt 2, on $(job_machine "$js"))"
  record total_s "$(elapsed "$t_kill" "$(now)")"
  record note "job interrupted $(elapsed "$t_kill" "$t_int") s and re-queued $(elapsed "$t_kill" "$t_req") s after the kill (lease ${EDGE_LEASE_MS} ms + grace ${EDGE_GRACE_MS} ms)"
  check "interrupted once, re-queued once" eq "$(count_to "$js" interrupted) $(count_to "$js" queued)" "1 2"
  ran_once "$js" 2
  ran_once "$tl" 1
  finish "$tl" "$js"
}

# 5. Freeze the cell's container (cgroup freezer) for longer than the DDS
#    lease, then thaw it: the edges drop and re-find the cell, nothing is
#    interrupted or run twice.
scenario_pause_cell() {
  record fault "freeze the cell mid-job (podman pause; netns: SIGSTOP) for ${PAUSE_S} s, then thaw it"
  start_cell || { fail "the cell did not come up"; finish; return; }
  local tl js t_pause t_unpause guids lost=() found=() t m
  tl=$(submit transfer_line.textproto)
  js=$(submit job_shop.json)
  wait_jobs 30 running "$tl" "$js" || fail "jobs not running"
  guids=$(be_trace edge-1 | dds_guids_of smc-cell)
  t_pause=$(now)
  be_pause cell
  sleep "$PAUSE_S"
  t_unpause=$(now)
  be_unpause cell
  wait_jobs 90 "done" "$tl" "$js" || fail "jobs not done after the unpause"
  for m in edge-1 edge-2; do
    # shellcheck disable=SC2086
    t=$(be_trace "$m" | dds_lost_after "$t_pause" $guids) && lost+=("$t")
    t=$(be_trace "$m" | dds_found_after "$t_unpause" smc-cell) && found+=("$t")
  done
  record detect_s "$(elapsed "$t_pause" "$(min_of "${lost[@]}")")"
  record detect_by "edges' DDS (cell's lease expired)"
  check "the edges dropped the frozen cell within the DDS lease (${DDS_LEASE_S} s)" \
    within "$(elapsed "$t_pause" "$(min_of "${lost[@]}")")" $((DDS_LEASE_S + 1))
  check "both edges found the cell again" eq "${#found[@]}" 2
  record recover_s "$(elapsed "$t_unpause" "$(max_of "${found[@]}")")"
  record recover_what "unpause -> both edges see the cell again"
  record total_s "$(elapsed "$t_pause" "$(now)")"
  local lost_lines
  lost_lines=$(be_logs cell | first_line_after "$t_pause" "lost \(liveliness\)" || true)
  record note "thawed cell logged a mill lost: $([[ -n "$lost_lines" ]] && echo yes || echo no)"
  check "nothing interrupted" eq "$(count_to "$js" interrupted)$(count_to "$tl" interrupted)" "00"
  ran_once "$tl" 1
  ran_once "$js" 1
  finish "$tl" "$js"
}
