#!/usr/bin/env bash
# Real IMU records end to end: the six axes of the tofupilot chamber cycle (gyro and accelerometer)
# and the three PAN LSM6DSM gyro axes, imported as a user would, then their metrics, a diagnosis
# of each whole record and the calibration board (every offset model and the memoriser, a control,
# fitted on some parts of a record, scored on the others), and the cross-part table (each part fitted
# alone, scored on every other: tofupilot's parts are the temperature branches of one power-on,
# PAN's the time blocks of one cooling; none is a separate run). Results under leaderboards/real-imu/.
# Usage (from the repository root, with tcbench installed): bash experiments/real-imu/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
here=experiments/real-imu
data=data/real                  # the repository's real recordings (data/real/README.md)
work=${WORK:-$here/runs}        # the imported recordings and the MLflow store (generated, git-ignored)
out=${OUT:-leaderboards/real-imu}
restarts=${RESTARTS:-5}
methods='methods=[raw,poly3,poly3_rate,bp,bp_gd,elman,model,memoriser]'  # the defaults and the memoriser
rm -rf "$work" "$out"
mkdir -p "$work"
export MLFLOW_TRACKING_URI="sqlite:///$PWD/$work/mlflow.db"
tofu="$data/tofupilot_imu_chamber/imu_raw_data.csv"
pan="$data/pan_lsm6dsm_tvac_cooling/pan_lsm6dsm_tvac_cooling.csv"
for f in "$tofu" "$pan"; do
    [[ -f $f ]] || { echo "run.sh: $f not found (data/real/README.md)" >&2; exit 2; }
done

echo "== import"
tcbench import "csv=$tofu" sensor=gyro time=timestamp:us temperature=imu.temperature:degC \
    output=imu.gyro.x:rad/s,imu.gyro.y:rad/s,imu.gyro.z:rad/s axes=x,y,z "out=$work/rec" name=tofupilot \
    device_id=tofupilot-imu
tcbench import "csv=$tofu" sensor=accel time=timestamp:us temperature=imu.temperature:degC \
    output=imu.acc.x:m/s^2,imu.acc.y:m/s^2,imu.acc.z:m/s^2 axes=x,y,z "out=$work/rec" name=tofupilot \
    device_id=tofupilot-imu
tcbench import "csv=$pan" sensor=gyro time=time_s:s temperature=temp_c:degC \
    output=gyro_x_dps:deg/s,gyro_y_dps:deg/s,gyro_z_dps:deg/s axes=x,y,z drop=spike_flag "out=$work/rec" name=pan \
    device_id=pan-etu-lsm6dsm

tofu_axes=$(printf "$work/rec/tofupilot-imu.%s.csv," gyro.x gyro.y gyro.z acc.x acc.y)
pan_axes=$(printf "$work/rec/pan-gyro_%s_dps.csv," x y z)
all="${tofu_axes}$work/rec/tofupilot-imu.acc.z.csv,${pan_axes%,}"

echo "== metrics"
tcbench metrics -m "recording=$all" "out=$out/metrics/\${stem:recording}" hydra.launcher.n_jobs=2
echo "== diagnosis of each whole record"
tcbench diagnose -m "recording=$all" "out=$out/diagnosis/\${stem:recording}"
echo "== calibration: tofupilot fitted on its first cooling branch, PAN on every other time block"
tcbench calibrate -m "recording=${tofu_axes%,}" "out=$out/calibration/\${stem:recording}" 'train_branches=[0]' \
    "restarts=$restarts" "$methods"
tcbench calibrate "recording=$work/rec/tofupilot-imu.acc.z.csv" true_input=-1:g 'train_branches=[0]' \
    "out=$out/calibration/tofupilot-imu.acc.z" "restarts=$restarts" "$methods"
tcbench calibrate -m "recording=${pan_axes%,}" "out=$out/calibration/\${stem:recording}" blocks=5 \
    'train_branches=[0,2,4]' drift_window_s=5 "restarts=$restarts" "$methods"
echo "== calibration: tofupilot fitted on its cooling and heating branches, scored on the second cooling"
tcbench calibrate -m "recording=${tofu_axes%,}" "out=$out/calibration-both/\${stem:recording}" 'train_branches=[0,1]' \
    "restarts=$restarts" "$methods"
tcbench calibrate "recording=$work/rec/tofupilot-imu.acc.z.csv" true_input=-1:g 'train_branches=[0,1]' \
    "out=$out/calibration-both/tofupilot-imu.acc.z" "restarts=$restarts" "$methods"
echo "== cross-part: tofupilot's branches of one power-on, each fitted alone and scored on the others (1, 2; 0 above)"
for i in 1 2; do
    tcbench calibrate -m "recording=${tofu_axes%,}" "out=$out/calibration-cross/\${stem:recording}.fit$i" \
        "train_branches=[$i]" "restarts=$restarts" "$methods"
    tcbench calibrate "recording=$work/rec/tofupilot-imu.acc.z.csv" true_input=-1:g "train_branches=[$i]" \
        "out=$out/calibration-cross/tofupilot-imu.acc.z.fit$i" "restarts=$restarts" "$methods"
done
echo "== cross-part: PAN's five time blocks of one cooling, each fitted alone and scored on the other four"
# one block spans 1.2 degC: too little for a diagnosis (2 degC at least), so no model here
for i in 0 1 2 3 4; do
    tcbench calibrate -m "recording=${pan_axes%,}" "out=$out/calibration-cross/\${stem:recording}.fit$i" blocks=5 \
        "train_branches=[$i]" drift_window_s=5 "restarts=$restarts" 'methods=[raw,poly3,poly3_rate,bp,bp_gd,elman,memoriser]'
done
echo "== board"
python "$here/summarise.py" --calibrations "$out/calibration" "$out/calibration-both" --cross "$out/calibration-cross" \
    --diagnoses "$out/diagnosis" --out "$out"
if [[ $out == leaderboards/real-imu ]]; then
    echo "== the README's tables and numbers, read from the board's CSVs"
    python -m tcbench.leaderboard.quoted "$here/README.md"
fi
