#!/usr/bin/env bash
# BBOB f1-f24 through ioh: every built-in single-objective optimiser and every installed peer,
# d = 5 and d = 20 (15 instances each), 10^4 d evaluations (NGOpt 50 d, TPE 200 trials:
# see README.md), IOHprofiler logs per run, then
# the committed leaderboards/bbob/.
# Usage (from the repository root, tcbench and plugins/tcbench-peers installed, python on PATH):
#   bash experiments/bbob/run.sh                 # the full sweep, TCBENCH_JOBS=2 workers
#   bash experiments/bbob/run.sh --methods fa,pso,cmaes --functions 1,15 --dims 5 --instances 5:1-2 \
#        --out-board experiments/bbob/smoke-board  # a smoke version (extra args go to sweep.py)
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/bbob
board=leaderboards/bbob
runs=$here/runs
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out-board) board=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
python "$here/sweep.py" --out "$runs" --jobs "${TCBENCH_JOBS:-2}" "${args[@]}"
rm -rf "$board"
python "$here/build.py" --runs "$runs" --out "$board" --ioh-merged "$here/ioh-analyzer"
