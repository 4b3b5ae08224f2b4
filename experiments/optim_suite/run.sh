#!/usr/bin/env bash
# The optimiser suite: every single-objective optimiser x 8 functions x {2, 10}-D x 15 seeds
# (shifted instances, 5000 evaluations) beside the peers of plugins/tcbench-peers (NGOpt on 10-D
# only), and MOPSO, GA (NSGA-II survival), NSGA-II and MOEA/D x ZDT1-3, DTLZ2 x 15 seeds; then
# the committed leaderboards/optim-suite/ (tables, convergence, fronts, ECDFs).
# Usage (from the repository root, with tcbench installed): bash experiments/optim_suite/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/optim_suite
export MLFLOW_TRACKING_URI="sqlite:///$PWD/$here/mlflow.db"
rm -f "$here/mlflow.db"
sweep=optim-suite-$(date -u +%Y%m%dT%H%M%S)
jobs=${TCBENCH_JOBS:-2}
tcbench run -m experiment=optim_suite hydra.launcher.n_jobs="$jobs" \
  tracking.plots=false "tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep-so"
tcbench run -m task=sphere,rastrigin,schaffer,rosenbrock,ackley,griewank,schwefel,levy task.dim=10 \
  task.shift=true task.target_precision=1e-8 budget=5000 optimiser=ngopt 'seed=range(15)' \
  tracking.experiment=optim-suite hydra.launcher.n_jobs="$jobs" tracking.plots=false "tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep-ngopt"
tcbench run -m experiment=optim_suite_mo hydra.launcher.n_jobs="$jobs" \
  tracking.plots=false "tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep-mo"
rm -rf leaderboards/optim-suite
tcbench leaderboard --experiment optim-suite --sweep "$sweep" --out leaderboards/optim-suite --ecdf overwrite=true
python "$here/summarise.py"
