"""The sensor-kind registry and its third kind, a capacitive MEMS accelerometer in g: simulated,
measured, imported from tables and PX4 logs, diagnosed and calibrated like the other kinds; and a
fourth kind added as one module."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import PX4_LOG

from tcbench.cli import main
from tcbench.metrics.report import analyse
from tcbench.sensors import kinds
from tcbench.sensors.kinds import unit
from tcbench.sensors.recording import read_recording, write_recording
from tcbench.sensors.simulate import simulate_recording

G0 = 9.80665


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


def test_the_registry_names_every_kind() -> None:
    assert kinds.names()[:3] == ["msra", "gyro", "accel"]
    accel = kinds.get("accel")
    assert accel.units == {"time_s": "s", "temperature_c": "degC", "input": "g", "output": "g"}
    assert sorted(accel.protocols) == ["chamber", "multipos", "static"]
    with pytest.raises(ValueError, match=r"unknown sensor 'baro'; known: msra, gyro, accel"):
        kinds.get("baro")
    with pytest.raises(ValueError, match="already exists"):
        kinds.register(accel)


@pytest.mark.figures
def test_chamber_metrics_recover_the_simulated_device(tmp_path: Path) -> None:
    """Through a chamber cycle the bias slope, noise density and flicker floor read from the
    recording are the device's own; heating and cooling open a loop (hysteresis and lag); the
    report draws the Allan and bias-against-temperature plots."""
    device = unit("accel", 0).model
    rec = simulate_recording("accel", "chamber", 0, 0)
    assert rec.meta.units["output"] == "g" and rec.input.max() == 0.0
    report = analyse(rec, tmp_path)
    m = report.metrics
    assert {p.name for p in report.files.values()} >= {"allan.png", "bias_vs_temperature.png"}
    assert all(p.stat().st_size > 5000 for p in report.files.values() if p.suffix == ".png")
    white_ug = device.effect("white_noise").params()["density"] * 1e6
    flicker_ug = device.effect("bias_instability").params()["b"] * 1e6
    assert m["bias_temp_slope_ug_per_c"] == pytest.approx(device.b1_mg_per_k * 1e3, rel=0.1)
    assert m["noise_density_ug_per_sqrt_hz"] == pytest.approx(white_ug, rel=0.15)
    assert m["vrw_m_per_s_per_sqrt_h"] == pytest.approx(m["noise_density_ug_per_sqrt_hz"] * 1e-6 * G0 * 60.0)
    assert m["bias_instability_ug"] > flicker_ug  # over a cycle the temperature drift lifts the floor
    assert m["hysteresis_bins"] >= 40 and m["hysteresis_width_ug"] > 3 * white_ug / np.sqrt(10.0)
    without = simulate_recording("accel", "chamber", 0, 0, without=("hysteresis", "thermal_lag", "warmup"))
    assert analyse(without).metrics["hysteresis_width_ug"] < 0.5 * m["hysteresis_width_ug"]


def test_static_and_multiposition_runs() -> None:
    device = unit("accel", 3).model
    static = analyse(simulate_recording("accel", "static", 3, 1)).metrics
    white_ug = device.effect("white_noise").params()["density"] * 1e6
    flicker_ug = device.effect("bias_instability").params()["b"] * 1e6
    assert static["noise_density_ug_per_sqrt_hz"] == pytest.approx(white_ug, rel=0.1)
    assert static["bias_instability_ug"] == pytest.approx(flicker_ug, rel=0.3)
    assert static["allan_min_is_interior"] == 1.0
    assert "hysteresis_width_ug" not in static and "bias_temp_slope_ug_per_c" not in static
    rec = simulate_recording("accel", "multipos", 3, 1)
    report = analyse(rec)
    assert report.nodes is not None and len(report.nodes) == 5
    assert report.metrics["sf_mean_g_per_g"] == pytest.approx(1.0, abs=0.01)
    # the four-position bias over the nodes follows the bias coefficient: ~b1 x the node spread
    spread_ug = abs(device.b1_mg_per_k) * 1e3 * np.std([-20, 0, 20, 40, 60], ddof=1)
    assert report.metrics["bias_variation_ug"] == pytest.approx(spread_ug, rel=0.25)


def test_accelerometer_tables_in_mg_and_m_s2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(0)
    n = 300
    acc_mg = rng.normal(-980.0, 1.0, n)
    pd.DataFrame({"t_ms": 10 * np.arange(n), "temp_f": np.linspace(50.0, 70.0, n), "az_mg": acc_mg,
                  "az_ms2": acc_mg * 1e-3 * G0}).to_csv(tmp_path / "imu.csv", sep=";", index=False)
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'imu.csv'}", "sensor=accel", "time=t_ms:ms",
                       "temperature=temp_f:degF", "output=az_mg:mg,az_ms2:m/s2", f"out={tmp_path / 'o'}",
                       "name=imu", "tracking.enabled=false")
    assert code == 0, err
    mg, ms2 = (read_recording(tmp_path / "o" / f"imu-{c}.csv") for c in ("az_mg", "az_ms2"))
    np.testing.assert_allclose(mg.output, acc_mg * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(ms2.output, mg.output, rtol=1e-12)
    np.testing.assert_allclose(mg.temperature_c[[0, -1]], [10.0, 21.0 + 1.0 / 9.0], rtol=1e-12)
    assert mg.meta.sensor == "accel" and mg.meta.units["output"] == "g"
    # a rate where an acceleration is meant, or a unit of nothing: one line, exit 2, nothing written
    for output, words in (("az_mg:deg/s", "not an acceleration"), ("az_mg:parsec", "not an acceleration")):
        code, _, err = run(capsys, "import", f"csv={tmp_path / 'imu.csv'}", "sensor=accel", "time=t_ms:ms",
                           "temperature=temp_f:degF", f"output={output}", f"out={tmp_path / 'bad'}",
                           "tracking.enabled=false")
        assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "bad").exists()
    # axes of different lengths (one column ends early): one line naming the cell, nothing written
    (tmp_path / "short.csv").write_text("t,temp,ax,ay\n0,25,1,1\n1,25.1,1,1\n2,25.2,1,\n3,25.3,1,\n")
    code, _, err = run(capsys, "import", f"csv={tmp_path / 'short.csv'}", "sensor=accel", "time=t:s", "temperature=temp:degC",
                       "output=ax:g,ay:g", f"out={tmp_path / 'bad'}", "tracking.enabled=false")
    assert code == 2 and err == [f"tcbench: error: {tmp_path / 'short.csv'}: row 3, column 'ay': empty cell"], err
    assert not (tmp_path / "bad").exists()


def test_a_px4_log_imports_every_accelerometer(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from pyulog import ULog

    code, out, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=accel", "out=rec", "name=px4")
    assert code == 0, err
    log = ULog(str(PX4_LOG), ["sensor_accel"])
    instances = {d.multi_id: d.data for d in log.data_list}
    assert sorted(instances) == [0, 1, 2]
    for i, data in instances.items():
        for axis in "xyz":
            rec = read_recording(workdir / "rec" / f"px4-sensor_accel-{i}-{axis}.csv")
            np.testing.assert_allclose(rec.output, data[axis].astype(np.float64) / G0, rtol=1e-12)
            np.testing.assert_allclose(rec.time_s, data["timestamp_sample"] * 1e-6, rtol=1e-15)
            assert rec.meta.sensor == "accel" and rec.meta.extra["source"]["topic"] == "sensor_accel"
        z = read_recording(workdir / "rec" / f"px4-sensor_accel-{i}-z.csv").output
        assert -1.02 < z.mean() < -0.97  # at rest, z along gravity
    assert out.count("tcbench: wrote ") == 9


def test_the_tofupilot_accelerometer_imports(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tcbench.datasets.real import TOFUPILOT_CSV

    axes = ",".join(f"imu.acc.{a}:m/s^2" for a in "xyz")
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=accel", "time=timestamp:us",
                       "temperature=imu.temperature:degC", f"output={axes}", f"out={tmp_path / 'rec'}", "name=imu",
                       "tracking.enabled=false")
    assert code == 0, err
    table = pd.read_csv(TOFUPILOT_CSV, sep="\t")
    for a in "xyz":
        rec = read_recording(tmp_path / "rec" / f"imu-imu.acc.{a}.csv")
        np.testing.assert_allclose(rec.output, table[f"imu.acc.{a}"].to_numpy() / G0, rtol=1e-14)
    z = read_recording(tmp_path / "rec" / "imu-imu.acc.z.csv")
    assert -1.0 < z.output.mean() < -0.95
    report = analyse(z)  # a real chamber cycle: bias against temperature and its heating/cooling loop
    assert report.metrics["hysteresis_bins"] >= 30 and np.isfinite(report.metrics["bias_temp_slope_ug_per_c"])


FOURTH_KIND = '''
"""A quartz vibrating-beam accelerometer: output a frequency in Hz (a test kind)."""
from dataclasses import dataclass

import numpy as np

from tcbench.sensors import effects as fx
from tcbench.sensors.kinds import SensorKind
from tcbench.sensors.models import SensorModel, Unit
from tcbench.sensors.protocols import Chamber, _from_segments
from tcbench.sensors.thermal import Segment


@dataclass(frozen=True)
class Beam(SensorModel):
    kind = "beam"
    f0_hz: float = 40000.0
    k_hz_per_g: float = 50.0
    tc_hz_per_k: float = -0.4

    def core(self, s):
        return self.f0_hz + self.k_hz_per_g * s.accel_g + self.tc_hz_per_k * (s.temp_die_c - self.ref_c)


def device(seed):
    rng = np.random.default_rng(seed)
    return Unit(f"beam-{seed}", Beam(tc_hz_per_k=-0.4 + rng.normal(0.0, 0.05),
                                     effects=(fx.WhiteNoise(0.002), fx.ThermalLag(120.0))))


def cycle(sample_rate_hz=10.0):
    segments = [Segment(25.0, 600.0, "", 0.0, 1.0), Segment(45.0, 900.0, "", 0.0, 1.0), Segment(5.0, 900.0, "", 0.0, 1.0)]
    return _from_segments("cycle", "beam", segments, 25.0, sample_rate_hz, Chamber())


KIND = SensorKind(name="beam", title="vibrating-beam accelerometer", input_unit="g", output_unit="Hz",
                  input_field="accel_g", input_range=(-100.0, 100.0), output_range=(0.0, 1.0e6),
                  device=device, protocols={"cycle": cycle}, noise_unit="mHz", noise_scale=1e3)
'''


def test_a_fourth_kind_is_one_module(tmp_path: Path) -> None:
    """A kind written as one module and registered simulates, round-trips through the schema,
    takes the schema's checks, and gets the generic metrics in its noise unit."""
    path = tmp_path / "beam_kind.py"
    path.write_text(FOURTH_KIND)
    spec = importlib.util.spec_from_file_location("beam_kind", path)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    sys.modules["beam_kind"] = module
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    kinds.register(module.KIND)
    try:
        rec = simulate_recording("beam", "cycle", 2, 0)
        assert rec.meta.units == {"time_s": "s", "temperature_c": "degC", "input": "g", "output": "Hz"}
        back = read_recording(write_recording(rec, tmp_path / "beam.csv"))
        np.testing.assert_array_equal(back.output, rec.output)
        m = analyse(back).metrics
        assert m["bias_temp_slope_mhz_per_c"] == pytest.approx(unit("beam", 2).model.tc_hz_per_k * 1e3, rel=0.1)  # the lag flattens it a little
        assert m["noise_density_mhz_per_sqrt_hz"] == pytest.approx(2.0, rel=0.15)
    finally:
        kinds.unregister("beam")
        sys.modules.pop("beam_kind", None)
    with pytest.raises(ValueError, match="unknown sensor 'beam'"):
        kinds.get("beam")


def _chamber_cycle(capsys: pytest.CaptureFixture[str]) -> str:
    """A simulated chamber cycle of accelerometer 0 written to rec/; its path."""
    code, _, err = run(capsys, "simulate", "sensor=accel", "protocol=chamber", "device_seed=0", "out=rec",
                       "tracking.enabled=false")
    assert code == 0, err
    return "rec/accel-chamber-dev0-seed0.csv"


@pytest.mark.slow  # a whole diagnosis; the accel chamber board's diagnosed row (tests/test_accel_chamber.py) stays in CI
def test_the_accelerometer_is_diagnosed(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A simulated chamber cycle: ``tcbench diagnose`` writes its model."""
    code, out, err = run(capsys, "diagnose", f"recording={_chamber_cycle(capsys)}", "out=diag", "tracking.enabled=false")
    assert code == 0, err
    assert "baseline RMSE held-out" in out and (workdir / "diag" / "model.yaml").is_file()


def test_the_accelerometer_is_calibrated_and_exported(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A simulated chamber cycle: ``tcbench calibrate`` fitted on the full cooling branch beats the raw output on
    the other branches, and ``tcbench export`` writes PX4's accelerometer parameters (TC_A*, in m/s^2)."""
    path = _chamber_cycle(capsys)
    code, out, err = run(capsys, "calibrate", f"recording={path}", "out=cal", "train_branches=[1]",
                         "methods=[raw,poly3]", "axis=z", "tracking.enabled=false")
    assert code == 0, err
    table = pd.read_csv(workdir / "cal" / "calibration.csv")
    test = table[table["role"] == "test"].pivot(index="branch", columns="method", values="drift_rms_g")
    assert (test["poly3"] < 0.5 * test["raw"]).all(), test
    code, out, err = run(capsys, "export", "calibrations=[cal]", "device_id=4", "out=params")
    assert code == 0, err
    script = (workdir / "params" / "px4_tc_params.txt").read_text().splitlines()
    assert script[-1] == "param set TC_A_ENABLE 1" and script[0] == "param set TC_A0_ID 4"
    x0 = float(next(ln.split()[3] for ln in script if ln.split()[2] == "TC_A0_X0_2"))
    assert abs(x0) < 0.5 * G0 and abs(x0) > 0  # m/s^2: the offset near TREF, in PX4's unit


def test_true_input_of_an_axis_along_gravity(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The tofupilot z axis reads about -1 g at rest: ``true_input=-1:g`` (or the same in m/s^2)
    makes the raw row its bias, not gravity; a bad value is one line and writes nothing."""
    from tcbench.datasets.real import TOFUPILOT_CSV

    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=accel", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.acc.z:m/s^2", f"out={tmp_path / 'rec'}",
                       "name=z", "tracking.enabled=false")
    assert code == 0, err
    boards = {}
    for spec in ("-1:g", f"{-G0}:m/s^2", None):
        out = tmp_path / f"cal{len(boards)}"
        args = [f"true_input={spec}"] if spec else []
        code, _, err = run(capsys, "calibrate", f"recording={tmp_path / 'rec' / 'z.csv'}", f"out={out}",
                           "methods=[raw,poly3]", *args, "tracking.enabled=false")
        assert code == 0, err
        boards[spec] = pd.read_csv(out / "calibration.csv").set_index(["method", "branch"])["drift_rms_g"]
    pd.testing.assert_series_equal(boards["-1:g"], boards[f"{-G0}:m/s^2"], rtol=1e-12)
    assert (boards["-1:g"]["raw"] < 0.1).all() and (boards[None]["raw"] > 0.9).all()
    np.testing.assert_allclose(boards["-1:g"]["poly3"], boards[None]["poly3"], rtol=1e-6)  # a constant is fitted
    for spec, words in (("-1:deg/s", "not an acceleration"), ("down", "expected VALUE[:unit]")):
        code, _, err = run(capsys, "calibrate", f"recording={tmp_path / 'rec' / 'z.csv'}", f"out={tmp_path / 'bad'}",
                           f"true_input={spec}", "tracking.enabled=false")
        assert code == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "bad").exists()
