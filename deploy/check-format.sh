#!/usr/bin/env bash
# Checks that every tracked C/C++ file is formatted as .clang-format says
# (clang-format --dry-run -Werror). deploy/test.sh runs it before building.
#
#   deploy/check-format.sh          check; list the files that differ
#   deploy/check-format.sh --fix    format them in place
set -euo pipefail
case "${1:-}" in
  "" | --fix) ;;
  -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  *) echo "check-format: unknown option '$1' (see --help)" >&2; exit 2 ;;
esac
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || { echo "check-format: clang-format not found; run deploy/setup.sh" >&2; exit 1; }
mapfile -t files < <(git ls-files '*.c' '*.h' '*.cpp' '*.hpp')
if [[ "${1:-}" == "--fix" ]]; then
  clang-format -i "${files[@]}"
  exit 0
fi
# One run over all files; the files that differ are the ones it names.
if ! out=$(clang-format --dry-run -Werror "${files[@]}" 2>&1); then
  mapfile -t bad < <(printf '%s\n' "$out" | grep -E '^[^ ]+:[0-9]+:[0-9]+: error' | cut -d: -f1 | sort -u)
  [[ ${#bad[@]} -gt 0 ]] || { printf '%s\n' "$out" >&2; exit 1; }
  echo "check-format: ${#bad[@]} of ${#files[@]} files differ from .clang-format:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix: deploy/check-format.sh --fix (or clang-format -i FILE)" >&2
  exit 1
fi
echo "check-format: ${#files[@]} files formatted"
