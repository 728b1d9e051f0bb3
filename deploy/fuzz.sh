#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz preset: clang, ASan + UBSan) and runs
# each one: first its kept crashes (tests/fuzz/regressions/TARGET, which must
# all pass now), then fuzzing from a corpus seeded with the project's shipped
# files, for S seconds per target. tests/fuzz/README.md says what each target
# covers.
#
#   deploy/fuzz.sh [--seconds S | --runs N] [--target NAME] [--jobs N]
#     --seconds S   fuzzing time per target (default 15; the long run is an
#                   hour: --seconds 3600); the corpus grows across runs
#     --runs N      N inputs per target from the seeds alone, with a fixed
#                   random seed: the same inputs every time (deploy/test.sh)
#     --target NAME only this target (fuzz_grafcet, fuzz_documents,
#                   fuzz_envelope, fuzz_frf_csv, fuzz_http)
#     --jobs N      parallel fuzzing processes per target (default 1)
#
# A crash stops the run with its input saved under build/fuzz/artifacts/TARGET
# and the command that replays it; fix it, then keep the input in
# tests/fuzz/regressions/TARGET (it then runs on every test).
set -euo pipefail
shopt -s nullglob
cd "$(dirname "$0")/.."
root=$PWD
seconds=15
runs=0
only=
jobs=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --target) only=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "fuzz: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
command -v clang++ >/dev/null || { echo "fuzz: clang not found; run deploy/setup.sh" >&2; exit 1; }

echo "== building the fuzz targets (fuzz preset: clang, libFuzzer, ASan + UBSan)"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
bin=$root/build/fuzz/fuzz
work=$root/build/fuzz/run
mkdir -p "$work"

# Seeds: the shipped documents. fuzz_documents' first byte picks the kind
# (bits 1..: 0 SupervisorConfig, 1 Job, 2 Catalog, 3 MillingModel,
# 4 ForceProcessModel) and the format (bit 0: JSON).
seed() {  # seed TARGET KIND_BYTE FILE...
  local t=$1 byte=$2; shift 2
  mkdir -p "$work/seeds/$t"
  for f in "$@"; do
    [[ -f $f ]] || continue
    { [[ -z $byte ]] || printf "\\x$byte"; cat "$f"; } >"$work/seeds/$t/$(basename "$f").$byte"
  done
}
rm -rf "$work/seeds"
seed fuzz_grafcet "" cell/grafcets/*.grafcet
seed fuzz_documents 00 edge/configs/*.textproto
seed fuzz_documents 02 cell/jobs/*.textproto
seed fuzz_documents 03 cell/jobs/*.json
seed fuzz_documents 04 cell/catalog/*.textproto
seed fuzz_documents 06 cell/models/paper_face_mill*.textproto cell/models/insperger*.textproto
seed fuzz_documents 08 cell/models/paper_force_model.textproto
seed fuzz_frf_csv "" tests/fuzz/seeds/frf/*.csv
seed fuzz_http "" tests/fuzz/seeds/http/*.bin
mkdir -p "$work/seeds/fuzz_envelope"

targets=(fuzz_grafcet fuzz_documents fuzz_envelope fuzz_frf_csv fuzz_http)
[[ -z $only ]] || targets=("$only")
printf "%-16s %12s %10s %8s\n" target executions "exec/s" corpus
for t in "${targets[@]}"; do
  [[ -x $bin/$t ]] || { echo "fuzz: no target '$t'" >&2; exit 2; }
  regress=$root/tests/fuzz/regressions/$t
  if compgen -G "$regress/*" >/dev/null; then
    "$bin/$t" -runs=0 "$regress"/* >"$work/$t.regressions.log" 2>&1 || {
      echo "fuzz: $t fails on a kept input (tests/fuzz/regressions/$t); log: $work/$t.regressions.log" >&2
      exit 1
    }
  fi
  corpus=$work/corpus/$t
  budget=(-max_total_time="$seconds")
  parallel=()
  if [[ $runs -gt 0 ]]; then
    # Deterministic: a fresh corpus, a fixed seed, a number of inputs.
    corpus=$work/corpus-fixed/$t
    rm -rf "$corpus"
    budget=(-runs="$runs" -seed=1)
  elif [[ $jobs -gt 1 ]]; then
    parallel=(-jobs="$jobs" -workers="$jobs")
  fi
  artifacts=$root/build/fuzz/artifacts/$t
  mkdir -p "$corpus" "$artifacts"
  log=$work/$t.log
  if ! (cd "$work" && "$bin/$t" "$corpus" "$work/seeds/$t" "${budget[@]}" "${parallel[@]}" -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$artifacts/" >"$log" 2>&1); then
    echo "fuzz: $t FOUND A CRASH (log: $log):" >&2
    grep -E "ERROR|SUMMARY|runtime error|Test unit written" "$log" | head -10 >&2
    echo "replay: $bin/$t $artifacts/<crash file>" >&2
    exit 1
  fi
  # With --jobs, each job's statistics are in fuzz-N.log beside the run, and
  # libFuzzer copies each job's log into the run's log when the job ends:
  # count them once, from the jobs' logs when there are any.
  if compgen -G "$work/fuzz-*.log" >/dev/null; then
    execs=$(cat "$work"/fuzz-*.log | awk '/stat::number_of_executed_units/ {s += $2} END {print s + 0}')
  else
    execs=$(awk '/stat::number_of_executed_units/ {s += $2} END {print s + 0}' "$log")
  fi
  rm -f "$work"/fuzz-*.log
  rate=$(grep -ho "exec/s: [0-9]*" "$log" | tail -1 | awk '{print $2}')
  printf "%-16s %12s %10s %8s\n" "$t" "$execs" "$rate" "$(ls "$corpus" | wc -l)"
done
echo "fuzz: no crash"
