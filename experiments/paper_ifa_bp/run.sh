#!/usr/bin/env bash
# Reproduce seed 000 §3 (Tables 1-2): FA-BP and IFA-BP, 30 trainings each, beside BP from random
# weights and from PSO's and CMA-ES's search (GD and LM), the polynomial baseline, raw and the
# oracle, on both MSRA tasks; then regenerate leaderboards/paper-ifa-bp/ and this folder's tables.
# Usage (from the repository root, with tcbench and plugins/tcbench-peers installed):
#   bash experiments/paper_ifa_bp/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/paper_ifa_bp
out=leaderboards/paper-ifa-bp
export MLFLOW_TRACKING_URI="sqlite:///$PWD/$here/mlflow.db"
rm -f "$here/mlflow.db"
sweep=paper-ifa-bp-$(date -u +%Y%m%dT%H%M%S)
common=("tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep" hydra/launcher=joblib hydra.launcher.n_jobs=2)
tcbench run -m experiment=paper_ifa_bp "${common[@]}"
# the baselines on the default tier (next_run) and on the replay (the test runs replay the training runs'
# power-on with new noise: what the boards measured before power-ons, for the seed claims' contrast)
tcbench run -m task=msra_zerobias,msra_fulltemp task.split=next_run,replay learner=raw,memoriser,lagpoly,poly \
  optimiser=none 'seed=range(30)' tracking.experiment=paper-ifa-bp "${common[@]}"
# the cubic fitted within runs (a constant per power-on: its turn-on bias), on both tiers
tcbench run -m task=msra_zerobias,msra_fulltemp task.split=next_run,replay learner=poly learner.offsets=per_run \
  optimiser=none 'seed=range(30)' tracking.experiment=paper-ifa-bp "${common[@]}"
# the limits on the same 30 draws (restart i on draw i: task.recordings_seed null, the default), on both tiers;
# one task per command: Hydra refuses a task.* override that does not sweep beside a sweep of task=
for task in msra_zerobias msra_fulltemp; do
  tcbench run -m task=$task task.split=next_run,replay learner=oracle,oracle_thermometer optimiser=none 'seed=range(30)' \
    tracking.experiment=paper-ifa-bp "${common[@]}"
done
# IFA-BP on the replay tier
for task in msra_zerobias msra_fulltemp; do
  tcbench run -m task=$task task.split=replay learner=bp learner.training=gd,lm optimiser=ifa 'seed=range(30)' \
    budget=510 tracking.experiment=paper-ifa-bp "${common[@]}"
done
# the cubic with the networks' inputs on zero bias: [T, dT/dt] (poly3_rate)
tcbench run -m task=msra_zerobias learner=poly learner.form=bias_rate optimiser=none 'seed=range(30)' \
  tracking.experiment=paper-ifa-bp "${common[@]}"
# Table 2 against the gradient-descent budget: one 300 000-epoch training per seed, scored after
# 1e3, 3e3, 1e4, 3e4, 1e5 epochs on the way (learner.checkpoints); IFA's search at the default
# 1 000 evaluations (the sweep above uses 510)
tcbench run -m task=msra_fulltemp learner=bp learner.training=gd learner.epochs=300000 budget=1000 \
  'learner.checkpoints=[1000,3000,10000,30000,100000]' optimiser=ifa 'seed=range(30)' \
  '+learner.label=IFA-BP-gd-300000ep' tracking.experiment=paper-ifa-bp "${common[@]}"
rm -rf "$out" && mkdir -p "$out"
tcbench leaderboard --experiment paper-ifa-bp --sweep "$sweep" --out "$out" overwrite=true
python "$here/tables.py" --experiment paper-ifa-bp --sweep "$sweep" --out "$out"
