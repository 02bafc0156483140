#!/usr/bin/env bash
# Run the integration tier (pytest -m integration: real nodes over DDS, the board emulator on a pty) several
# times in a row beside CPU-bound processes, as on a busy CI machine, and print one line per run.
# Usage: tools/integration_under_load.sh [RUNS (3)] [BURNERS (2)] [-- extra pytest arguments]
# Exit status 0 only if every run passed. Logs: out/under_load/run-K.log.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
runs="${1:-3}"; burners="${2:-2}"
shift $(( $# > 2 ? 2 : $# ))
[ "${1:-}" = "--" ] && shift
case "$runs$burners" in *[!0-9]*) echo "usage: $0 [RUNS] [BURNERS] [-- pytest arguments]" >&2; exit 2 ;; esac
cd "$ROOT"
source tools/bootstrap.sh
mkdir -p out/under_load

pids=()
stop_burners() { [ "${#pids[@]}" = 0 ] || kill "${pids[@]}" 2>/dev/null || true; }
trap stop_burners EXIT
for _ in $(seq "$burners"); do
  python -c 'while True: pass' &      # one busy core each
  pids+=("$!")
done
echo "[under load] $burners CPU-bound processes beside $runs runs of the integration tier ($(nproc) cores)"

failed=0
for k in $(seq "$runs"); do
  log="out/under_load/run-$k.log"
  start=$SECONDS
  if python -m pytest -m integration -p no:cacheprovider -q "$@" >"$log" 2>&1; then verdict=passed; else verdict=FAILED; failed=1; fi
  summary="$(grep -E '^(=+ )?[0-9]+ (passed|failed)|(passed|failed|error).* in [0-9.]+s' "$log" | tail -1 | sed 's/=//g')"
  echo "[under load] run $k of $runs: $verdict in $((SECONDS - start)) s: ${summary# }"
  [ "$verdict" = passed ] || grep -E '^(FAILED|ERROR) ' "$log" | sed 's/^/[under load]   /' || true
done
exit "$failed"
