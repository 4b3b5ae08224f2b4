#!/usr/bin/env bash
# The accelerometer chamber task's board on the next_run tier (new power-ons): BP (IFA and random
# initial weights; GD and LM) and BAS-Elman over 30 restarts on device 0; the baselines (raw, the
# memoriser, poly3, poly3_rate, lagpoly, the diagnosed model) and both limits on devices 0-9, restart i
# on draw i of the cycles; the new_device, new_profile and replay tiers on device 0; then
# leaderboards/accel-chamber/ (one board per device and tier, and devices.md across them).
# Usage (from the repository root, tcbench installed): bash experiments/accel_chamber/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/accel_chamber
out=leaderboards/accel-chamber
export MLFLOW_TRACKING_URI="sqlite:///$PWD/$here/mlflow.db"
rm -f "$here/mlflow.db"
sweep=accel-chamber-$(date -u +%Y%m%dT%H%M%S)
common=("tracking.sweep_id=$sweep" hydra.sweep.dir="multirun/$sweep" hydra.launcher.n_jobs=2)
# The default tier, next_run: the test cycles are new power-ons of the device. Restart i of every row
# trains and tests on draw i of the cycles (task.recordings_seed null, the default).
tcbench run -m experiment=accel_chamber "${common[@]}"
tcbench run -m task=accel_chamber learner=elman optimiser=bas 'seed=range(30)' budget=510 \
  tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber 'task.device_seed=range(10)' \
  learner=raw,memoriser,lagpoly,model,oracle,oracle_thermometer optimiser=none 'seed=range(30)' \
  tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber 'task.device_seed=range(10)' learner=poly learner.form=bias,bias_rate \
  optimiser=none 'seed=range(30)' tracking.experiment=accel-chamber "${common[@]}"
# The fitted learners let to extrapolate (task.clamp_inputs=false: rows named -unclamped) beside the
# default's, which hold their test inputs to the training range.
tcbench run -m task=accel_chamber task.clamp_inputs=false learner=poly learner.form=bias,bias_rate optimiser=none \
  'seed=range(30)' tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber task.clamp_inputs=false learner=bp learner.training=gd,lm optimiser=ifa \
  'seed=range(30)' budget=510 tracking.experiment=accel-chamber "${common[@]}"
# The other tiers on device 0: new_device (other units of the lot), new_profile (a programme the
# training never saw) and replay (the diagnostic the boards stood on before power-ons: the test
# cycles replay the training cycles' power-on with new noise); IFA-BP over 30 restarts on each.
tcbench run -m task=accel_chamber task.split=new_device,new_profile,replay \
  learner=raw,memoriser,lagpoly,model,oracle,oracle_thermometer optimiser=none 'seed=range(30)' \
  tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber task.split=new_device,new_profile,replay learner=poly learner.form=bias,bias_rate \
  optimiser=none 'seed=range(30)' tracking.experiment=accel-chamber "${common[@]}"
tcbench run -m task=accel_chamber task.split=new_device,new_profile,replay learner=bp learner.training=gd,lm \
  optimiser=ifa 'seed=range(30)' budget=510 tracking.experiment=accel-chamber "${common[@]}"
rm -rf "$out" && mkdir -p "$out"
tcbench leaderboard --experiment accel-chamber --sweep "$sweep" --out "$out" overwrite=true
python "$here/devices.py" --boards "$out"
python "$here/pairs.py" --sweep "$sweep"  # the paired tests README.md quotes
