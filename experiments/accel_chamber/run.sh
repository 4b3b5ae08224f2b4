#!/usr/bin/env bash
# The accelerometer chamber task's board: BP (IFA and random initial weights; GD and LM) over 30
# seeds, BAS-Elman over 10, and the baselines (raw, poly3, poly3_rate, lagpoly, the diagnosed model,
# both oracles) on device 0; the baselines on devices 1-9; then leaderboards/accel-chamber/ (one board
# per device, and devices.md across them). About 40 min on 2 cores.
# Usage (from the repository root, tcbench installed): bash experiments/accel_chamber/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/accel_chamber
out=leaderboards/accel-chamber
export MLFLOW_TRACKING_URI="sqlite:///$PWD/$here/mlflow.db"
rm -f "$here/mlflow.db"
sweep=accel-chamber-$(date -u +%Y%m%dT%H%M%S)
common=("tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep" hydra.launcher.n_jobs=2)
tcbench run -m experiment=accel_chamber "${common[@]}"
tcbench run -m task=accel_chamber learner=elman optimiser=bas 'seed=range(10)' budget=510 \
  tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber learner=raw,oracle,oracle_thermometer,lagpoly,model optimiser=none \
  tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber learner=poly learner.form=bias,bias_rate optimiser=none \
  tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber 'task.device_seed=range(1,10)' \
  learner=raw,oracle,oracle_thermometer,lagpoly,model optimiser=none tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber 'task.device_seed=range(1,10)' learner=poly learner.form=bias,bias_rate \
  optimiser=none tracking.experiment=accel-chamber "${common[@]}"
rm -rf "$out" && mkdir -p "$out"
tcbench leaderboard --experiment accel-chamber --sweep "$sweep" --out "$out"
python "$here/devices.py" --boards "$out"
