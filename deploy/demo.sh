#!/usr/bin/env bash
# The demo cell on loopback: a cell service with a seeded database, two
# simulated mills and the dashboard; submits one transfer-line job (SMC I)
# and one job-shop job (SMC II) and prints a live summary until both finish.
# This is the README's demo command; it installs what it needs first.
#
#   deploy/demo.sh [--speedup N] [--learn N] [--keep] [--linuxcnc] [--insecure]
#     --speedup N  machine seconds per wall second for the simulated mills (default 2)
#     --learn N    then submit the job-shop part N times in a row on one mill
#                  (mill-1; mill-2 with --linuxcnc): the cell learns its models
#                  and promotes it to SMC I (cell/README.md, "Learning and
#                  promotion"); prints smc-cell part show and plots its runs
#     --keep       leave the cell running after the jobs finish (Ctrl-C ends it)
#     --linuxcnc   mill-1 is a headless LinuxCNC (deploy/linuxcnc/) whose own
#                  motion cuts the paper's part through the virtual
#                  dynamometer, in real time; mill-2 stays simulated
#     --insecure   plain DDS: no authentication, access control or signing
#                  (a quick local run). By default the demo runs under DDS
#                  Security: a fresh PKI (deploy/security/pki.sh) and each
#                  process on its own identity and permissions, each mill's
#                  edge confined to its own partition
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

speedup=2
learn=0
keep=0
linuxcnc=0
secure=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --speedup) speedup="$2"; shift 2 ;;
    --learn) learn="$2"; shift 2 ;;
    --keep) keep=1; shift ;;
    --linuxcnc) linuxcnc=1; shift ;;
    --insecure) secure=0; shift ;;
    --secure) secure=1; shift ;;  # the default; kept for older scripts
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "demo: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

deploy/setup.sh
echo "== building (ci preset: the same build tree and flags as deploy/test.sh)"
cmake --preset ci >/dev/null
targets=(smc-cell smc-edge smc-dashboard smc-mtconnect)
[[ $linuxcnc -eq 0 ]] || targets+=(smc_dyno)
cmake --build --preset ci --target "${targets[@]}"
bin=$root/build/release/bin

export CYCLONEDDS_URI="file://$root/deploy/cyclonedds/loopback.xml"
run=$(mktemp -d /tmp/smc-demo.XXXXXX)
partition="demo-$$"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  [[ $linuxcnc -eq 0 ]] || deploy/linuxcnc/run.sh stop --dir "$run/linuxcnc" >/dev/null 2>&1 || true
  echo "demo: logs and database kept in $run"
}
trap cleanup EXIT INT TERM

# The DDS profile of a process: its own identity's (each participant
# authenticated, its topics as its role allows), or with --insecure the
# loopback one.
uri() { [[ $secure -eq 1 ]] && echo "file://$run/pki/$1/cyclonedds.xml" || echo "$CYCLONEDDS_URI"; }
if [[ $secure -eq 1 ]]; then
  echo "== DDS Security: a PKI in $run/pki (deploy/security/README.md; --insecure: without)"
  deploy/security/pki.sh init "$run/pki" --machines mill-1,mill-2 | sed 's/^/   /'
  deploy/security/pki.sh issue "$run/pki" mtconnect observer | sed 's/^/   /'
fi

echo "== cell database (seeded): $run/cell.db"
"$bin/smc-cell" db init --db "$run/cell.db" --seed

echo "== starting the cell service and two simulated mills (DDS on loopback, partition $partition)"
CYCLONEDDS_URI=$(uri cell) "$bin/smc-cell" serve --db "$run/cell.db" --partition "$partition" \
  >"$run/cell.log" 2>&1 &
pids+=($!)
# Each simulated mill cuts with its own "true" model: mill-1 is the machine the
# cell's database describes; mill-2 differs from it (tool 25 % softer, 30 %
# less damped, material 20 % harder: cell/models/paper_face_mill_mismatched.textproto).
declare -A true_model=(
  [mill-1]="$root/cell/models/paper_face_mill.textproto"
  [mill-2]="$root/cell/models/paper_face_mill_mismatched.textproto"
)
mills=(mill-1 mill-2)
if [[ $linuxcnc -eq 1 ]]; then
  echo "   mill-1 is LinuxCNC (its log: $run/linuxcnc/linuxcnc.log), cutting the paper's part"
  chmod 755 "$run"
  deploy/linuxcnc/run.sh start --dir "$run/linuxcnc" --dyno "$root/edge/configs/smc2.textproto"
  mkdir -p "$run/programs" && chmod 777 "$run/programs"
  # LinuxCNC's user runs mill-1's edge: it owns mill-1's identity (key 600).
  [[ $secure -eq 0 ]] || chown -R "${SMC_CNC_USER:-smc-cnc}" "$run/pki/edge-mill-1"
  deploy/linuxcnc/run.sh exec env CYCLONEDDS_URI="$(uri edge-mill-1)" "$bin/smc-edge" run \
    --machine mill-1 --drive linuxcnc --partition "$partition" --no-realtime \
    --program-dir "$run/programs" >"$run/mill-1.log" 2>&1 &
  pids+=($!)
  mills=(mill-2)
fi
for m in "${mills[@]}"; do
  echo "   $m cuts as $(basename "${true_model[$m]}")"
  CYCLONEDDS_URI=$(uri "edge-$m") "$bin/smc-edge" run --machine "$m" --partition "$partition" \
    --paced --speedup "$speedup" --mill-model "${true_model[$m]}" >"$run/$m.log" 2>&1 &
  pids+=($!)
done
if [[ -x "$bin/smc-dashboard" ]]; then
  token=$(head -c 24 /dev/urandom | od -An -tx1 | tr -d ' \n')
  # The token file holds the token's SHA-256, not the token.
  ( umask 077; echo "$token" | "$bin/smc-dashboard" --hash-token operator >"$run/tokens" )
  # Secure: HTTPS with a certificate from the PKI's web CA.
  web=(--http 127.0.0.1:8080)
  scheme=http
  if [[ $secure -eq 1 ]]; then
    deploy/security/pki.sh https "$run/pki" dashboard 127.0.0.1 localhost >/dev/null
    web+=(--tls-cert "$run/pki/dashboard/https.pem" --tls-key "$run/pki/dashboard/https.key")
    scheme=https
  fi
  CYCLONEDDS_URI=$(uri dashboard) "$bin/smc-dashboard" "${web[@]}" \
    --partition "$partition" --token-file "$run/tokens" --cell-db "$run/cell.db" \
    >"$run/dashboard.log" 2>&1 &
  pids+=($!)
  echo "== dashboard:     $scheme://127.0.0.1:8080/"
  echo "   operator link: $scheme://127.0.0.1:8080/#token=$token   (feed hold, release, chatter signal)"
  if [[ $secure -eq 1 ]]; then
    echo "   its certificate comes from the demo's web CA: trust $run/pki/ca/web_ca.pem"
    echo "   (browser: import it as an authority; curl --cacert $run/pki/ca/web_ca.pem ...)"
  fi
fi

CYCLONEDDS_URI=$(uri mtconnect) "$bin/smc-mtconnect" --listen 127.0.0.1:7878 \
  --partition "$partition" >"$run/mtconnect.log" 2>&1 &
pids+=($!)
echo "== MTConnect adapter: 127.0.0.1:7878 (SHDR; devices: mtconnect/Devices.xml)"

echo "== submitting a transfer-line job (SMC I), a job-shop job (SMC II) and an extended"
echo "   job-shop job (SMC II+: chatter moved to a stable spindle speed)"
tl=$("$bin/smc-cell" job submit "$root/cell/jobs/transfer_line.textproto" --db "$run/cell.db" | awk '{print $1}')
js=$("$bin/smc-cell" job submit "$root/cell/jobs/job_shop.json" --db "$run/cell.db" | awk '{print $1}')
plus_job="$root/cell/jobs/job_shop_plus.textproto"
if [[ $linuxcnc -eq 1 ]]; then
  # LinuxCNC's drive (mill-1) has no spindle-speed override, which SMC II+'s
  # module O needs (its edge refuses the job, naming why): cut it on mill-2.
  plus_job=$run/job_shop_plus_mill-2.textproto
  { cat "$root/cell/jobs/job_shop_plus.textproto"; echo 'machine_id: "mill-2"'; } >"$plus_job"
fi
jp=$("$bin/smc-cell" job submit "$plus_job" --db "$run/cell.db" | awk '{print $1}')
"$bin/smc-cell" watch "$tl" "$js" "$jp" --db "$run/cell.db" --interval 3 --timeout 600

echo
grep -hE "chatter|candidate force model|validated|promoted" "$run/cell.log" | sed 's/^/  /' || true
if [[ $learn -gt 0 ]]; then
  on=mill-1
  [[ $linuxcnc -eq 0 ]] || on=mill-2
  echo "== learning: part housing-js submitted $learn times in a row on $on"
  printf 'part_id: "housing-js"\nmachine_id: "%s"\n' "$on" >"$run/learn.textproto"
  for ((i = 1; i <= learn; ++i)); do
    id=$("$bin/smc-cell" job submit "$run/learn.textproto" --db "$run/cell.db" | awk '{print $1}')
    echo "-- run $i of $learn: job $id"
    "$bin/smc-cell" watch "$id" --db "$run/cell.db" --interval 5 --timeout 600 | tail -n 2
  done
  "$bin/smc-cell" part show housing-js --db "$run/cell.db" --plot "$run/housing-js-runs.svg"
fi
if [[ $keep -eq 1 ]]; then
  echo "demo: the cell keeps running; Ctrl-C to stop"
  wait
fi
