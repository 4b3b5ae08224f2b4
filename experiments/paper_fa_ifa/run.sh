#!/usr/bin/env bash
# Reproduce seed 000 §2.2.3 (Figs. 3-4): FA vs IFA on Schaffer and Rastrigin, 30 seeds,
# then regenerate the committed leaderboards and this folder's figures and results table.
# Usage (from the repository root, with tcbench installed): bash experiments/paper_fa_ifa/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/paper_fa_ifa
export MLFLOW_TRACKING_URI="sqlite:///$PWD/$here/mlflow.db"
rm -f "$here/mlflow.db"
sweep=paper-fa-ifa-$(date -u +%Y%m%dT%H%M%S)
tcbench run -m experiment=paper_fa_ifa "tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep"
tcbench leaderboard --experiment paper-fa-ifa --sweep "$sweep" --out leaderboards/paper-fa-ifa overwrite=true
python "$here/analyse.py" --sweep "$sweep" --out "$here"
