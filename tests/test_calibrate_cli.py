"""``tcbench calibrate`` on the real tofupilot chamber cycle as a user imports it: fitted on the
first cooling branch, scored on the heating and the second cooling branch, tracked in MLflow; by
default fitted on the branches that span the held-out temperatures."""

from __future__ import annotations

import json
from pathlib import Path

import mlflow
import numpy as np
import pandas as pd
import pytest
from conftest import PAN_CSV

from tcbench.cli import main
from tcbench.datasets.real import TOFUPILOT_CSV


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


@pytest.fixture()
def gyro_y(workdir: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.y:rad/s", "out=rec", "name=gyro-y",
                       "tracking.enabled=false")
    assert code == 0, err
    return workdir / "rec" / "gyro-y.csv"


@pytest.mark.figures
def test_calibrate_the_tofupilot_gyro(gyro_y: Path, workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "calibrate", f"recording={gyro_y}", "out=cal", "train_branches=[0]")
    assert code == 0, err
    table = pd.read_csv(workdir / "cal" / "calibration.csv")
    assert sorted(set(table["method"])) == ["bp", "bp_gd", "elman", "model", "poly3", "poly3_rate", "raw"]
    assert table.groupby("method")["direction"].apply(list).to_dict()["raw"] == ["cooling", "heating", "cooling"]
    drift = table.pivot(index="branch", columns="method", values="drift_rms_deg_per_s")
    assert (table.loc[table["branch"] == 0, "role"] == "train").all()
    assert (drift.loc[[1, 2], "poly3"] < 0.7 * drift.loc[[1, 2], "raw"]).all()  # held out: the cubic still helps
    assert (drift.loc[0, "poly3"] < 0.05 * drift.loc[0, "raw"])  # in sample: it fits
    assert (drift.loc[[1, 2], "bp"] < drift.loc[[1, 2], "raw"]).all()
    # the diagnosed model (its quadratic core carries on beyond the cooling branch's 51.6 degC, where
    # PX4's cubic is held at its edge) leaves less than half the cubic's held-out drift (0.31x and 0.20x)
    assert (drift.loc[[1, 2], "model"] < 0.5 * drift.loc[[1, 2], "poly3"]).all(), drift
    assert "sensor: gyro" in (workdir / "cal" / "diagnosis" / "model.yaml").read_text()
    assert not (workdir / "cal" / "px4_tc_params.txt").exists()  # one axis alone: tcbench export writes them
    assert (workdir / "cal" / "residuals.png").stat().st_size > 10_000
    lines = out.strip().splitlines()
    assert lines[0].startswith("calibrate gyro-y.csv (gyro, output in deg/s): fitting raw, poly3, poly3_rate, bp, bp_gd, "
                               "elman, model on temperature branch 0 (cooling 51.6 -> -17.5 degC); scoring on "
                               "temperature branches 1, 2 (held out)"), lines[0]
    summary = json.loads((workdir / "cal" / "calibration.json").read_text())
    best = next(ln for ln in lines if ln.startswith("best held out"))  # the last line but MLflow's
    assert best.startswith(f"best held out: {summary['best']}, drift ") and "95% block bootstrap" in best, best
    assert summary["best"] == "model" and summary["next"] in {"bp", "bp_gd", "elman", "poly3", "poly3_rate"}
    assert summary["ratio_lo"] <= summary["ratio_to_next"] <= summary["ratio_hi"]
    # every ratio carries its interval; a method the interval cannot tell from the best is a tie
    for m, (point, lo, hi) in summary["x_best"].items():
        assert lo <= point <= hi and (m in summary["tied"]) == (m != summary["best"] and lo <= 1.0), m
    assert (": a tie with" in best) == bool(summary["tied"]) and summary["ratio_hi"] < 1.0 and not summary["tied"]
    assert all(summary["x_raw"][m][0] < 1.0 for m in ("poly3", "model")) and summary["worse_than_raw"] == []
    parts = summary["per_part"]  # each held-out branch on its own: the fit-on-one-run, test-on-another answer
    assert [p["part"] for p in parts] == ["gyro-y:1", "gyro-y:2"]
    for p in parts:
        assert p["best"] == min(p["drift"], key=p["drift"].get) and p["x_raw"]["raw"] == [1.0, 1.0, 1.0]
        assert all(lo <= x <= hi for x, lo, hi in p["x_raw"].values())
    md = (workdir / "cal" / "calibration.md").read_text()
    for words in ("- bp: LM (at most 200 iterations", "- bp_gd: GD (at most 1000 epochs; ran 1000",
                  "- elman: ADAM (at most 500 epochs", "- model: tcbench diagnose on the screened training parts",
                  "0 of 2687 training samples dropped"):
        assert words in md, words
    held = table[table["role"] == "test"]
    pooled = {m: np.sqrt(np.average(g["drift_rms_deg_per_s"] ** 2)) for m, g in held.groupby("method")}
    assert min(pooled, key=pooled.get) == summary["best"]  # the ranking agrees with the long table
    assert len(lines) < 20 and "| raw | 1 | heating |" not in out  # the long table goes to the file

    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (r,) = client.search_runs([client.get_experiment_by_name("calibrations").experiment_id])
    assert r.data.tags["tcbench.kind"] == "calibration" and r.data.tags["tcbench.sensor"] == "gyro"
    assert r.data.metrics["poly3.b1.drift_rms"] == pytest.approx(drift.loc[1, "poly3"])
    assert r.data.metrics["model.held_out.drift"] == pytest.approx(summary["best_drift"])
    assert r.data.tags["tcbench.data_hash"] == summary["content_hash"]
    assert {"calibration.md", "calibration.json", "residuals.png", "model.yaml", "report.md"} <= \
        {a.path for a in client.list_artifacts(r.info.run_id)}


def test_the_default_split_fits_the_branches_that_span_the_held_out_temperatures(
        gyro_y: Path, workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A simulated oven record (5.2 h: a warm-up from 26 to 61 degC, then steps down to -39 degC)
    was fitted on its warm-up by default and scored 66 % beyond the fitted range; now the branch
    spanning the held-out temperatures is fitted, and the line under the first says why. On the
    tofupilot cycle that is the heating (-17.6..74.0 degC), the two coolings held out inside it.
    ``train_branches=`` still chooses, and the share beyond the fitted range is still printed."""
    code, _, err = run(capsys, "simulate", "sensor=gyro", "protocol=oven", "protocol_params.sample_rate_hz=1",
                       "protocol_params.hold_s=600", "metrics=false", "out=sim", "name=oven", "tracking.enabled=false")
    assert code == 0, err
    for rec, fitted, held in (("sim/oven.csv", [1], [0]), (str(gyro_y), [1], [0, 2])):
        code, out, err = run(capsys, "calibrate", f"recording={rec}", "out=cal", "methods=[raw,poly3]",
                             "overwrite=true", "tracking.enabled=false")
        assert code == 0, err
        about = json.loads((workdir / "cal" / "calibration.json").read_text())
        assert (about["fitted"], about["held_out_parts"]) == (fitted, held), rec
        assert about["range"]["beyond_share"] < 0.001 and "held out beyond the fitted" not in out, about["range"]
        why = out.splitlines()[1]
        assert why.startswith("  why: this branch spans the held-out temperatures best") and "0.0% of the held-out" \
            in why and "train_branches= chooses" in why, why
        assert about["fitted_why"] == why.strip()
    code, out, err = run(capsys, "calibrate", "recording=sim/oven.csv", "out=cal", "methods=[raw,poly3]",
                         "train_branches=[0]", "overwrite=true", "tracking.enabled=false")
    assert code == 0, err
    about = json.loads((workdir / "cal" / "calibration.json").read_text())
    assert about["range"]["beyond_share"] > 0.6 and "held out beyond the fitted" in out  # the old default
    assert about["fitted_why"] == "" and "  why:" not in out


@pytest.mark.parametrize(("args", "words"), [
    (("train_branches=[5]",), "the recording has 3 temperature branches"),
    (("methods=[elman_magic]",), "methods: unknown method 'elman_magic'; known: raw, poly3, poly3_rate, bp, bp_gd, "
                                 "elman, model, memoriser; did you mean 'elman'?"),
    (("min_swing_c=0",), "must be > 0"),
    (("seed=-1",), "seed must be a non-negative integer"),
    (("restarts=0",), "restarts must be 1..1000"),
    (("blocks=100000",), "blocks=100000: blocks must be 1..8400"),
    (("true_input=-1:furlong",), "true_input=-1:furlong"),
])
def test_bad_calibrations_are_one_line(gyro_y: Path, workdir: Path, capsys: pytest.CaptureFixture[str],
                                       args: tuple[str, ...], words: str) -> None:
    code, _, err = run(capsys, "calibrate", f"recording={gyro_y}", "out=cal", *args)
    assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (workdir / "cal").exists() and not (workdir / "mlflow.db").exists()


def test_a_seed_sweep_resolves_each_seed_and_never_shares_an_output(gyro_y: Path, workdir: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """``out=cal/${seed}`` is resolved per job (the launcher composed one config per group of
    seeds, so every seed wrote into the first seed's folder); seeds writing one folder are refused."""
    code, _, err = run(capsys, "calibrate", "-m", f"recording={gyro_y}", "seed=range(2)", "methods=[bp]",
                       "out=cal/${seed}", "tracking.enabled=false")
    assert code == 0, err
    boards = [pd.read_csv(workdir / "cal" / s / "calibration.csv") for s in ("0", "1")]
    assert boards[0]["drift_rms_deg_per_s"].tolist() != boards[1]["drift_rms_deg_per_s"].tolist()
    code, _, err = run(capsys, "calibrate", "-m", f"recording={gyro_y}", "seed=range(2)", "methods=[raw]",
                       "out=same", "tracking.enabled=false")
    assert code == 2 and len(err) == 1 and "jobs 1 and 2 of the sweep would both write same" in err[0], err
    assert not (workdir / "same").exists()


def test_a_record_that_only_cools_is_cut_into_time_blocks(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The PAN gyro cools once (one branch): with nothing said, it is cut into five time blocks,
    fitted on 0, 2, 4 and scored on the two between — held out, and the first line says so —, the
    cubic far below the raw bias there; ``blocks=``/``train_branches=`` choose otherwise."""
    code, _, err = run(capsys, "import", f"csv={PAN_CSV}", "sensor=gyro", "time=time_s:s", "temperature=temp_c:degC",
                       "output=gyro_x_dps:deg/s", "drop=spike_flag", "out=rec", "name=pan-x",
                       "tracking.enabled=false")
    assert code == 0, err
    code, out, err = run(capsys, "calibrate", "recording=rec/pan-x.csv", "out=cal", "methods=[raw,poly3]",
                         "drift_window_s=5", "tracking.enabled=false")
    assert code == 0, err
    assert out.splitlines()[0] == ("calibrate pan-x.csv (gyro, output in deg/s): fitting raw, poly3 on time blocks "
                                   "0, 2, 4; scoring on time blocks 1, 3 (held out)"), out
    table = pd.read_csv(workdir / "cal" / "calibration.csv")
    assert list(table.loc[table["method"] == "raw", "role"]) == ["train", "test", "train", "test", "train"]
    drift = table.pivot(index="branch", columns="method", values="drift_rms_deg_per_s")
    assert (drift.loc[[1, 3], "poly3"] < 0.01 * drift.loc[[1, 3], "raw"]).all()
    assert "5 time blocks (blocks=5, as the record has one temperature branch)" in \
        (workdir / "cal" / "calibration.md").read_text()
    summary = json.loads((workdir / "cal" / "calibration.json").read_text())
    assert summary["best"] == "poly3" and summary["ratio_hi"] < 0.01  # far below raw, and the interval says so
    code, out, err = run(capsys, "calibrate", "recording=rec/pan-x.csv", "out=cal2", "blocks=4", "train_branches=[0,1,2,3]",
                         "methods=[raw,poly3]", "tracking.enabled=false")
    assert code == 0 and err == ["tcbench: warning: every part is fitted and no test_recordings= is given: the "
                                 "scores are in-sample and no method is ranked"], err
    assert "nothing held out: no method is ranked" in out
    code, _, err = run(capsys, "calibrate", "recording=rec/pan-x.csv", "out=bad", "blocks=0", "tracking.enabled=false")
    assert code == 2 and len(err) == 1 and "blocks=0" in err[0], err


def test_network_restarts_are_summarised_by_their_median(gyro_y: Path, workdir: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "calibrate", f"recording={gyro_y}", "out=cal3", "restarts=3", "methods=[raw,bp]",
                       "tracking.enabled=false")
    assert code == 0, err
    board = pd.read_csv(workdir / "cal3" / "calibration.csv").set_index(["method", "branch"])
    assert board.loc["bp", "restarts"].eq(3).all() and board.loc["raw", "restarts"].eq(1).all()
    single = []
    for seed in range(3):
        code, _, err = run(capsys, "calibrate", f"recording={gyro_y}", f"out=one{seed}", f"seed={seed}",
                           "methods=[bp]", "tracking.enabled=false")
        assert code == 0, err
        single.append(pd.read_csv(workdir / f"one{seed}" / "calibration.csv")["drift_rms_deg_per_s"].to_numpy())
    assert len({tuple(s) for s in single}) == 3  # three different networks
    pd.testing.assert_series_equal(board.loc["bp", "drift_rms_deg_per_s"].reset_index(drop=True),
                                   pd.Series(np.median(single, axis=0), name="drift_rms_deg_per_s"))
    assert "3 restarts each (seeds 0..2)" in (workdir / "cal3" / "calibration.md").read_text()


def test_fitted_on_one_recording_scored_on_another(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The tofupilot gyro y cut in two recordings: fitted on the first (its cooling), scored on every
    part of the second; the cubic's scores there are those of the cubic fitted by hand."""
    from tcbench.compensation.calibration import fit, record, residual, scores
    from tcbench.datasets.real import tofupilot_gyro
    from tcbench.sensors.recording import make_recording, write_recording
    from tcbench.signal.branches import temperature_branches

    full = tofupilot_gyro("y")
    cut = int(np.searchsorted(full.time_s, 40 * 60.0))
    for name, rows, sensor, scale in (("first", slice(0, cut), "gyro", 1.0), ("second", slice(cut, None), "gyro", 1.0),
                                      ("accel", slice(cut, None), "accel", 1e-3)):
        write_recording(make_recording(full.time_s[rows], full.temperature_c[rows], full.input[rows],
                                       full.output[rows] * scale, sensor=sensor,
                                       sample_rate_hz=full.meta.sample_rate_hz, device_id="tofu"),
                        workdir / f"{name}.csv")
    code, _, err = run(capsys, "calibrate", "recording=first.csv", "test_recordings=[second.csv]", "out=cal",
                       "methods=[raw,poly3]")
    assert code == 0, err
    table = pd.read_csv(workdir / "cal" / "calibration.csv")
    second = table[table["recording"] == "second"]
    assert (second["role"] == "test").all() and set(table["recording"]) == {"first", "second"}
    whole = record(full.time_s, full.temperature_c, full.output, full.input)
    first_branch = temperature_branches(full.time_s[:cut], full.temperature_c[:cut])[0]
    res = residual(fit("poly3", [whole.part(first_branch.start, first_branch.stop)]), whole.part(cut, full.time_s.size))
    parts = temperature_branches(full.time_s[cut:], full.temperature_c[cut:])
    assert len(second) == 2 * len(parts)
    for k, part in enumerate(parts):
        expected = scores(res[part.start:part.stop], full.time_s[cut:][part.start:part.stop])["drift_rms"]
        got = second.loc[(second["method"] == "poly3") & (second["branch"] == k), "drift_rms_deg_per_s"]
        assert float(got.iloc[0]) == pytest.approx(expected, rel=1e-9)
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (r,) = client.search_runs([client.get_experiment_by_name("calibrations").experiment_id])
    assert "poly3.second.b0.drift_rms" in r.data.metrics and "poly3.b0.drift_rms" in r.data.metrics

    for others, words in (("[first.csv]", "two recordings named 'first'"),
                          ("[accel.csv]", "accel.csv records accel output in g, not gyro output in deg/s")):
        code, _, err = run(capsys, "calibrate", "recording=first.csv", f"test_recordings={others}", "out=bad",
                           "tracking.enabled=false")
        assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (workdir / "bad").exists()


def test_a_short_record_is_calibrated_without_the_diagnosed_model(workdir: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """12 minutes of the tofupilot gyro: the default methods run, the model is left out with one
    line saying why (blocks 0, 2, 4 of five: 7.2 min; a diagnosis needs 20 min), and the rest are ranked
    on the held-out parts."""
    from tcbench.datasets.real import tofupilot_gyro
    from tcbench.sensors.recording import make_recording, write_recording

    full = tofupilot_gyro("x")
    keep = full.time_s - full.time_s[0] < 12 * 60
    short = make_recording(full.time_s[keep], full.temperature_c[keep], full.input[keep], full.output[keep],
                           sensor="gyro", sample_rate_hz=full.meta.sample_rate_hz, device_id="short")
    write_recording(short, workdir / "short.csv")
    code, out, err = run(capsys, "calibrate", "recording=short.csv", "out=cal", "tracking.enabled=false")
    assert code == 0, err
    assert err == ["tcbench: model left out: the fitted parts last 7.2 min and a diagnosis needs 20 min "
                   "(tcbench diagnose reports what a short record can tell)"], err
    summary = json.loads((workdir / "cal" / "calibration.json").read_text())
    assert set(summary["drift"]) == {"raw", "poly3", "poly3_rate", "bp", "bp_gd", "elman"}


def test_the_residual_plot_envelope_keeps_every_spike_in_few_points() -> None:
    from tcbench.commands.calibration import _envelope

    rng = np.random.default_rng(4)
    x, y = np.arange(86_400.0), rng.normal(size=86_400)
    y[[5, 40_000, 86_399]] = [30.0, -40.0, 25.0]  # spikes, one in the unbinned tail
    ex, ey = _envelope(x, y, points=4000)
    assert ex.size <= 4100 and (np.diff(ex) > 0).all()
    assert {30.0, -40.0, 25.0} <= set(ey.tolist())
    small = _envelope(x[:50], y[:50])
    assert small[0].size == 50
