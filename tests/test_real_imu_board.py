"""The real-IMU board (experiments/real-imu/summarise.py) on calibrations of the real tofupilot gyro:
held-out drift per method and split, each split named for what it is, the winner, the white-noise
floor of the drift score with its interval."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tcbench.cli import main
from tcbench.datasets.real import TOFUPILOT_CSV

SUMMARISE = Path(__file__).resolve().parents[1] / "experiments" / "real-imu" / "summarise.py"


def _summarise():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("real_imu_summarise", SUMMARISE)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def test_the_board_of_two_splits(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us", "temperature=imu.temperature:degC",
                 "output=imu.gyro.y:rad/s", "out=rec", "name=tofu-y", "tracking.enabled=false"]) == 0
    for folder, train in (("one", "[0]"), ("both", "[0,1]")):
        assert main(["calibrate", "recording=rec/tofu-y.csv", f"out={folder}/tofu-y", f"train_branches={train}",
                     "methods=[raw,poly3,poly3_rate]", "tracking.enabled=false"]) == 0
    capsys.readouterr()
    summarise = _summarise()
    long, wide = summarise.board([workdir / "one", workdir / "both"], workdir / "nowhere")
    assert list(wide["fit on → scored on"]) == ["0 → 1,2", "0,1 → 2"]
    one = pd.read_csv(workdir / "one" / "tofu-y" / "calibration.csv")
    test = one[(one["method"] == "poly3") & (one["role"] == "test")]["drift_rms_deg_per_s"]
    assert wide.loc[0, "poly3"] == pytest.approx(float(np.sqrt(np.mean(test ** 2))))
    # the best's own drift and its ratio to raw's, the RMS over parts (the README's tables quote them)
    best_drift = np.array([wide.loc[i, b] for i, b in enumerate(wide["best"])])
    np.testing.assert_array_equal(wide["best's drift"], best_drift)
    np.testing.assert_allclose(wide["best's drift / raw"], best_drift / wide["raw"], rtol=1e-12)
    best_over_raw = wide["best / raw"].str.split().str[0].astype(float)  # "0.408 [0.158, 0.476]": with its interval
    assert (wide["best"] != "raw").all() and (best_over_raw < 1).all()
    assert wide["best / raw"].str.match(r"^[0-9.]+ \[[0-9.]+, [0-9.]+\]$").all()
    # the branches of one recording are named so, never runs
    assert set(long["split_kind"]) == set(wide["split kind"]) == {"branches of one power-on"}
    # the floor, with its interval: the held-out branches' sample-to-sample sigma (here the plain
    # std of their first differences) over the root of the samples in a 60-s window at 1.98 Hz
    from tcbench.sensors.recording import read_recording

    rec = read_recording(workdir / "rec" / "tofu-y.csv")
    held = one[(one["method"] == "raw") & (one["role"] == "test")]["branch"].tolist()
    from tcbench.signal.branches import temperature_branches

    parts = temperature_branches(rec.time_s, rec.temperature_c)
    diffs = np.concatenate([np.diff(rec.output[parts[k].start:parts[k].stop]) for k in held])
    first = long[long["split"] == "0 → 1,2"]
    floor, lo, hi = (first[c].iloc[0] for c in ("noise_floor", "noise_floor_lo", "noise_floor_hi"))
    assert floor == pytest.approx(np.std(diffs) / np.sqrt(2.0) / np.sqrt(round(60 * 1.97862)), rel=0.15)
    assert lo < floor < hi and wide.loc[0, "noise floor"].startswith(f"{floor:.3g} [")
    np.testing.assert_allclose(first["ratio_to_floor"], first["held_out_drift"] / floor, rtol=1e-9)
    assert (first["ratio_to_floor_lo"] <= first["ratio_to_floor"]).all()
    assert (first["ratio_to_floor"] <= first["ratio_to_floor_hi"]).all()
    # at the floor only when the interval reaches 1: nothing here comes near white noise
    assert (long["at_floor"] == (long["ratio_to_floor_lo"] <= 1)).all() and not long["at_floor"].any()
    assert (wide["at the floor"] == "none").all()
    assert set(long["split"]) == {"0 → 1,2", "0,1 → 2"} and len(long) == 6
    # fitted on one part, scored on another: the pairs named for what they are
    pairs, tally = summarise.cross([workdir / "one", workdir / "both"])
    assert set(pairs["split_kind"]) == {"branches of one power-on"} and set(pairs["fit part"]) == {0}
    assert sorted(set(pairs["test part"])) == [1, 2] and "split_kind" in tally


def test_each_split_is_named_for_what_it_is() -> None:
    kind = _summarise().split_kind
    branches = pd.DataFrame({"recording": "r", "branch": [0, 1, 2], "direction": ["cooling", "heating", "cooling"]})
    blocks = pd.DataFrame({"recording": "r", "branch": [0, 1, 2, 3, 4], "direction": "cooling"})
    cycle = blocks.assign(direction=["cooling", "cooling", "heating", "heating", "heating"])
    about = {"recording": "r.csv", "held_out_parts": [1, 2], "test_recordings": []}
    assert kind(about | {"parts": "3 temperature branches (min_swing_c=3 degC)"}, branches) == "branches of one power-on"
    assert kind(about | {"parts": "5 time blocks (blocks=5)"}, blocks) == "time blocks of one cooling"
    assert kind(about | {"parts": "5 time blocks (blocks=5)"}, cycle) == "time blocks of one power-on"
    # another recording's parts are runs; the record's own parts stay what they are
    assert kind(about | {"parts": "3 temperature branches (min_swing_c=3 degC)", "test_recordings": ["s.csv"]},
                branches) == "branches of one power-on + runs"
    assert kind(about | {"parts": "1 temperature branch", "held_out_parts": [], "test_recordings": ["s.csv"]},
                branches.iloc[:1]) == "runs"
