#!/usr/bin/env bash
# The headless LinuxCNC mill of this folder (smc-mill.ini).
#
#   deploy/linuxcnc/run.sh start [--dir DIR] [--dyno CONFIG [--plant MODEL]]
#                                               start it; return once it is ready
#                                               (out of E-stop, on, homed)
#   deploy/linuxcnc/run.sh stop [--dir DIR]    stop it (the display exits, LinuxCNC
#                                               shuts down)
#   deploy/linuxcnc/run.sh exec CMD [ARGS]     run CMD as the mill's user, e.g.
#                                               exec deploy/linuxcnc/smc-cnc run p.ngc
#   deploy/linuxcnc/run.sh foreground [--dir DIR]
#
# LinuxCNC's rtapi_app refuses to run as root, so as root the mill runs as the
# user smc-cnc (created when missing; SMC_CNC_USER to change), and so must
# every program that talks to it (exec). Its configuration is copied to DIR
# (default /tmp/smc-linuxcnc), which that user owns: LinuxCNC writes its
# parameter and position files there. Log: DIR/linuxcnc.log. One LinuxCNC per
# host (fixed System V keys). As root, start gives LinuxCNC's realtime threads
# SCHED_FIFO priority 70 (SMC_CNC_RT_PRIORITY; 0 leaves them as they start).
#
# --dyno CONFIG puts the virtual dynamometer (smc_dyno, built with the edge)
# in the servo thread: LinuxCNC's own motion then cuts the part of CONFIG (a
# SupervisorConfig, as for smc-edge simulate --config) and the force pins
# read its forces; --plant MODEL cuts it on a mill that is not the model.
# The module is installed into LinuxCNC's module folder (root), from
# SMC_DYNO_MODULE (default build/release/lib/smc_dyno.so).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
user=${SMC_CNC_USER:-smc-cnc}
dir=/tmp/smc-linuxcnc
dyno_config=
dyno_plant=
action=${1:-}
[[ $# -gt 0 ]] && shift
case "$action" in
  -h|--help|"") sed -n '2,19p' "$0"; [[ -n $action ]]; exit $? ;;
esac

as=()
home=$HOME
if [[ $(id -u) -eq 0 ]]; then
  id "$user" >/dev/null 2>&1 || useradd --system --create-home --shell /usr/sbin/nologin "$user"
  as=(runuser -u "$user" --)
  home=$(getent passwd "$user" | cut -d: -f6)
fi
# A minimal environment: LinuxCNC's Python modules are for /usr/bin/python3,
# and its tool table shared memory is found through HOME.
env_of=(env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME="$home")

if [[ $action == exec ]]; then
  exec "${as[@]}" "${env_of[@]}" "$@"
fi

while [[ $# -gt 0 ]]; do
  case "$1" in
    --dir) dir=$2; shift 2 ;;
    --dyno) dyno_config=$(realpath "$2"); shift 2 ;;
    --plant) dyno_plant=$(realpath "$2"); shift 2 ;;
    *) echo "run.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

case "$action" in
  stop)
    [[ -d $dir ]] && touch "$dir/stop"
    for _ in $(seq 1 200); do
      pgrep -x milltask >/dev/null || pgrep -x rtapi_app >/dev/null || exit 0
      sleep 0.1
    done
    echo "run.sh: LinuxCNC did not stop within 20 s (see $dir/linuxcnc.log)" >&2
    exit 1 ;;
  start|foreground) ;;
  *) echo "run.sh: unknown command '$action' (see --help)" >&2; exit 2 ;;
esac

command -v linuxcnc >/dev/null || { echo "run.sh: LinuxCNC is not installed: run deploy/setup.sh" >&2; exit 1; }
if pgrep -x milltask >/dev/null; then
  echo "run.sh: a LinuxCNC is already running on this host (one per host): stop it first" >&2
  exit 1
fi
rm -rf "$dir"
mkdir -p "$dir"
cp "$here"/smc-mill.ini "$here"/smc-mill.hal "$here"/smc-edge.hal "$here"/smc-mill.tbl \
  "$here"/smc-display "$dir"/
if [[ -n $dyno_config ]]; then
  [[ -r $dyno_config ]] || { echo "run.sh: --dyno $dyno_config: no such file" >&2; exit 2; }
  [[ -z $dyno_plant || -r $dyno_plant ]] || { echo "run.sh: --plant $dyno_plant: no such file" >&2; exit 2; }
  module=${SMC_DYNO_MODULE:-$here/../../build/release/lib/smc_dyno.so}
  [[ -f $module ]] || { echo "run.sh: $module: not built (cmake --build --preset ci)" >&2; exit 1; }
  rtlib=/usr/lib/linuxcnc/modules  # LinuxCNC 2.9 loads realtime modules only from here
  install -m644 "$module" "$rtlib/smc_dyno.so" || {
    echo "run.sh: cannot install the dynamometer into $rtlib (run as root)" >&2; exit 1; }
  sed "s|@CONFIG@|$dyno_config|; s|@PLANT@|${dyno_plant:+ plant=$dyno_plant}|" \
    "$here"/smc-dyno.hal.in >"$dir"/smc-dyno.hal
  sed -i 's/^HALFILE = smc-edge.hal$/HALFILE = smc-dyno.hal\nHALFILE = smc-edge.hal/' "$dir"/smc-mill.ini
fi
[[ ${#as[@]} -eq 0 ]] || chown -R "$user" "$dir"
launch=("${as[@]}" "${env_of[@]}" SMC_CNC_READY="$dir/ready" SMC_CNC_STOP="$dir/stop"
  linuxcnc -r "$dir/smc-mill.ini")
cd "$dir"
if [[ $action == foreground ]]; then
  exec "${launch[@]}"
fi
# LinuxCNC's realtime threads (the servo thread, rtapi_app:T#N) get
# SCHED_FIFO only from a setuid-root rtapi_app; run as the mill's user they
# are ordinary threads, which a busy host starved past the edge's 250 ms
# stale-record limit (3 runs in 36 with two CPU hogs). As root, give them
# the FIFO priority a realtime install would (SMC_CNC_RT_PRIORITY, default
# 70; 0 leaves them as they are). Best effort: without CAP_SYS_NICE (some
# containers) they stay as they are, and the log says so.
realtime_threads() {
  local prio=${SMC_CNC_RT_PRIORITY:-70} app t
  [[ $prio -gt 0 && $(id -u) -eq 0 ]] || return 0
  app=$(pgrep -x rtapi_app | head -1)
  [[ -n $app ]] || return 0
  for t in /proc/"$app"/task/*; do
    [[ $(cat "$t/comm" 2>/dev/null) == rtapi_app:T* ]] || continue
    chrt -f -p "$prio" "${t##*/}" >/dev/null 2>&1 ||
      echo "run.sh: could not give LinuxCNC's thread ${t##*/} SCHED_FIFO $prio (no CAP_SYS_NICE?): a busy host may stall it" >&2
  done
}
setsid "${launch[@]}" >"$dir/linuxcnc.log" 2>&1 </dev/null &
pid=$!
for _ in $(seq 1 300); do
  if [[ -f $dir/ready ]]; then
    realtime_threads
    echo "run.sh: LinuxCNC ready (config and log in $dir; stop: $0 stop --dir $dir)"
    exit 0
  fi
  if ! kill -0 "$pid" 2>/dev/null; then
    echo "run.sh: LinuxCNC exited before it was ready ($dir/linuxcnc.log):" >&2
    tail -20 "$dir/linuxcnc.log" >&2
    exit 1
  fi
  sleep 0.1
done
echo "run.sh: LinuxCNC not ready within 30 s (see $dir/linuxcnc.log)" >&2
exit 1
