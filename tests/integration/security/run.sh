#!/usr/bin/env bash
# DDS Security end to end (deploy/security/pki.sh): a cell and an edge run
# with their identities and permissions; a job completes. While it cuts, an
# outside program (smc-c-client, the C API and the IDL alone) tries to hold
# the mill's feed:
#   - with no certificate (the plain loopback profile): the edge never obeys;
#   - with a certificate from another CA: the edge never obeys;
#   - with a valid identity whose permissions do not allow operator
#     commands (an observer): refused when it creates its writer;
#   - with the dashboard's identity: obeyed, right after the refusals.
# And mill-2's edge certificate tries to act as mill-1: an edge started as
# mill-1 on it is refused at start; its chatter-event writer in mill-1's
# partition is refused; a chatter event about mill-1 written from its own
# partition is dropped by the cell, which logs the refusal.
# Then, while the job still cuts, certificates are rotated: the dashboard's
# (its new identity commands the mill, which was not restarted) and the
# cell's (the cell restarts on its new one and goes on tracking the job,
# which completes on its first attempt).
# Usage: run.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin=$1
src=$2
work=$(mktemp -d /tmp/smc-security-XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; for f in "$work"/*.log; do echo "--- $f" >&2; tail -5 "$f" >&2; done; exit 1; }

"$src/deploy/security/pki.sh" init "$work/pki" --machines mill-1,mill-2 >/dev/null
"$src/deploy/security/pki.sh" issue "$work/pki" observer observer >/dev/null
"$src/deploy/security/pki.sh" init "$work/rogue" --machines mill-1 >/dev/null  # another CA
partition="security-$$"
profile() { echo "file://$work/pki/$1/cyclonedds.xml"; }

"$bin/smc-cell" db init --db "$work/cell.db" --seed >/dev/null
CYCLONEDDS_URI=$(profile cell) "$bin/smc-cell" serve --db "$work/cell.db" --partition "$partition" \
  >"$work/cell.log" 2>&1 &
pids+=($!)
CYCLONEDDS_URI=$(profile edge-mill-1) "$bin/smc-edge" run --machine mill-1 --partition "$partition" \
  --paced --no-realtime --mill-model "$src/cell/models/paper_face_mill.textproto" \
  >"$work/edge.log" 2>&1 &
pids+=($!)
printf 'part_id: "housing-js"\nmachine_id: "mill-1"\n' >"$work/job.textproto"
job=$("$bin/smc-cell" job submit "$work/job.textproto" --db "$work/cell.db" | awk '{print $1}')

state() { "$bin/smc-cell" job list --db "$work/cell.db" | awk -v j="$job" '$1 == j {print $2}'; }
for _ in $(seq 1 150); do
  [[ "$(state)" == running ]] && break
  sleep 0.2
done
[[ "$(state)" == running ]] || fail "the job did not start under DDS Security (state $(state))"
echo "ok: the job runs with every participant authenticated and access-controlled"

client() {  # client PROFILE_URI TIMEOUT LOG [ARGS...] -> exit status of smc-c-client
  local rc=0 uri=$1 timeout=$2 log=$3
  shift 3
  CYCLONEDDS_URI=$uri "$bin/smc-c-client" --machine mill-1 --partition "$partition" \
    --operator intruder --timeout "$timeout" "$@" >"$work/$log.log" 2>&1 || rc=$?
  echo "$rc"
}

rc=$(client "file://$src/deploy/cyclonedds/loopback.xml" 4 no-certificate)
[[ $rc == 1 ]] || fail "no certificate: smc-c-client exited $rc (1: the mill did not obey)"
echo "ok: no certificate: the mill did not obey"

rc=$(client "file://$work/rogue/dashboard/cyclonedds.xml" 4 other-ca)
[[ $rc == 1 ]] || fail "another CA: smc-c-client exited $rc (1: the mill did not obey)"
grep -q "Certificate not valid" "$work/edge.log" || fail "the edge did not log the foreign certificate"
echo "ok: a certificate from another CA: the mill did not obey; the edge logged: $(grep -m1 -o 'Certificate not valid[^(]*' "$work/edge.log")"

rc=$(client "$(profile observer)" 4 observer)
[[ $rc == 2 ]] || fail "an observer: smc-c-client exited $rc (2: its command writer refused)"
grep -q "writer" "$work/observer.log" || fail "the observer's refusal is not reported"
echo "ok: a valid identity without the right to command: its writer refused ($(head -1 "$work/observer.log"))"

# mill-2's edge certificate, acting as mill-1.
rc=0
CYCLONEDDS_URI=$(profile edge-mill-2) timeout 30 "$bin/smc-edge" run --machine mill-1 \
  --partition "$partition" --paced --no-realtime \
  --mill-model "$src/cell/models/paper_face_mill.textproto" >"$work/edge-posing.log" 2>&1 || rc=$?
[[ $rc != 0 && $rc != 124 ]] || fail "an edge on mill-2's certificate ran as mill-1 (exit $rc)"
grep -qi "not allowed by security" "$work/edge-posing.log" ||
  fail "the edge on mill-2's certificate did not say why it stopped"
echo "ok: an edge on mill-2's certificate cannot run as mill-1 ($(grep -m1 -i 'not allowed by security' "$work/edge-posing.log" | cut -c1-200))"

rc=$(client "$(profile edge-mill-2)" 4 posing-in-mill-1 --posing-from mill-1)
[[ $rc == 2 ]] || fail "mill-2's certificate in mill-1's partition: smc-c-client exited $rc (2: writer refused)"
echo "ok: mill-2's certificate cannot write into mill-1's partition ($(head -1 "$work/posing-in-mill-1.log"))"

rc=$(client "$(profile edge-mill-2)" 10 posing-from-mill-2 --posing-from mill-2)
[[ $rc == 0 ]] || fail "mill-2's certificate in its own partition: smc-c-client exited $rc (0: written)"
for _ in $(seq 1 50); do
  grep -q "refused on smc_chatter_event: a sample about machine 'mill-1' from a writer in machine 'mill-2''s partition" \
    "$work/cell.log" && break
  sleep 0.2
done
grep -q "refused on smc_chatter_event: a sample about machine 'mill-1'" "$work/cell.log" ||
  fail "the cell did not report the chatter event mill-2's certificate wrote about mill-1"
echo "ok: a chatter event about mill-1 from mill-2's partition is dropped: $(grep -m1 -o 'refused on smc_chatter_event.*' "$work/cell.log")"

rc=$(client "$(profile dashboard)" 20 dashboard)
[[ $rc == 0 ]] || fail "the dashboard's identity: smc-c-client exited $rc (0: the mill obeyed)"
echo "ok: the dashboard's identity holds and releases the feed right after"

# Rotation while the job cuts (pki.sh issue over an existing name: a new key
# and certificate; processes load theirs at start).
[[ "$(state)" == running ]] || fail "the job is no longer running before the rotation ($(state))"
old_cell=$(openssl x509 -in "$work/pki/cell/identity.pem" -noout -serial)
"$src/deploy/security/pki.sh" issue "$work/pki" dashboard dashboard >/dev/null
rc=$(client "$(profile dashboard)" 20 dashboard-rotated)
[[ $rc == 0 ]] || fail "the dashboard's rotated identity: smc-c-client exited $rc (0: the mill obeyed)"
echo "ok: the dashboard's certificate rotated while the job cuts: the new one commands the mill"
"$src/deploy/security/pki.sh" issue "$work/pki" cell cell >/dev/null
[[ "$(openssl x509 -in "$work/pki/cell/identity.pem" -noout -serial)" != "$old_cell" ]] ||
  fail "pki.sh issue did not make the cell a new certificate"
kill "${pids[0]}"
wait "${pids[0]}" 2>/dev/null || true
CYCLONEDDS_URI=$(profile cell) "$bin/smc-cell" serve --db "$work/cell.db" --partition "$partition" \
  >"$work/cell-rotated.log" 2>&1 &
pids[0]=$!
echo "ok: the cell restarted on its rotated certificate while the job cuts (state $(state))"

for _ in $(seq 1 600); do
  case "$(state)" in done | failed) break ;; esac
  sleep 0.2
done
[[ "$(state)" == done ]] || fail "the job did not finish (state $(state))"
"$bin/smc-cell" job show "$job" --db "$work/cell.db" | head -1 | grep -q "(attempt 1)" ||
  fail "the job was dispatched again: $("$bin/smc-cell" job show "$job" --db "$work/cell.db" | head -1)"
grep -q "edge mill-1" "$work/cell-rotated.log" ||
  fail "the cell on its rotated certificate never heard from the edge"
echo "ok: the job completed on its first attempt across both rotations"
echo "PASS: DDS Security: the job completed across two rotations; 3 intruders and mill-2's edge acting as mill-1 refused, the operator obeyed"
