"""Fitted-model files: format round trip, simulation from a spec, errors, ``tcbench simulate model=``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tcbench.cli import main
from tcbench.diagnose.model_file import (
    ModelFileError,
    ModelSpec,
    parse_model,
    read_model,
    spec_from_model,
    to_sensor_model,
    write_model,
)
from tcbench.sensors.fitted import PolynomialModel
from tcbench.sensors.models import MSRA, Gyro
from tcbench.sensors.protocols import Profile
from tcbench.sensors.simulate import simulate_recording

SPEC = ModelSpec(
    sensor="msra", centre_c=10.0, half_range_c=50.0, bias=(150.0, -8.0, 0.5),
    scale_factor=(200.0, 1.0, -0.3),
    effects={"quantisation": {"step": 1e-4}, "thermal_lag": {"tau_s": 420.0},
             "warmup": {"amplitude": 0.01, "tau_s": 900.0}, "white_noise": {"density": 0.0024}},
)

GOOD = """\
tcbench_model: 1
sensor: msra
output_unit: Hz
core:
  kind: polynomial
  centre_c: 10.0
  half_range_c: 50.0
  bias: [150.0, -8.0, 0.5]
  scale_factor: [200.0, 1.0, -0.3]
effects:
  thermal_lag: {tau_s: 420.0}
  white_noise: {density: 0.0024}
"""


def profile(temp_c: np.ndarray, accel_g: float = 0.0, rate_dps: float = 0.0, sensor: str = "msra",
            rate_hz: float = 1.0) -> Profile:
    """A profile with the given temperature (degC) per sample and constant inputs."""
    t = np.arange(temp_c.size) / rate_hz
    return Profile("test", sensor, rate_hz, t, temp_c, np.full(t.size, accel_g), np.zeros(t.size),
                   np.full(t.size, rate_dps))


def test_round_trip(tmp_path: Path) -> None:
    path = write_model(SPEC, tmp_path / "model.yaml")
    assert read_model(path) == SPEC
    assert not [p for p in tmp_path.iterdir() if p.name != "model.yaml"]  # no temporary left
    assert spec_from_model(to_sensor_model(SPEC)) == SPEC
    text = path.read_text()
    assert "tcbench_model: 1" in text and "output_unit: Hz" in text


def test_example_file_reads(tmp_path: Path) -> None:
    (tmp_path / "m.yaml").write_text(GOOD)
    spec = read_model(tmp_path / "m.yaml")
    assert spec.bias == (150.0, -8.0, 0.5) and spec.effects["thermal_lag"] == {"tau_s": 420.0}
    # YAML 1.1 reads 1e-3 as a string: still a number here
    spec = parse_model({**_data(), "effects": {"white_noise": {"density": "1e-3"}}}, "x.yaml")
    assert spec.effects["white_noise"]["density"] == 1e-3


def test_sensor_model_build() -> None:
    model = to_sensor_model(SPEC)
    assert isinstance(model, PolynomialModel) and model.kind == "msra" and model.ref_c == 10.0
    assert [e.id for e in model.effects] == ["thermal_lag", "warmup", "white_noise", "quantisation"]
    assert model.describe()["effects"]["thermal_lag"] == {"tau_s": 420.0}
    assert model.without("warmup").with_effects({"thermal_lag": {"tau_s": 60.0}}).effect("thermal_lag").tau_s == 60.0
    assert MSRA().kind == "msra" and Gyro().kind == "gyro"
    assert PolynomialModel(sensor="gyro").kind == "gyro"
    with pytest.raises(ValueError, match="half_range_c"):
        PolynomialModel(half_range_c=0.0)


@pytest.mark.parametrize(("sensor", "accel", "rate"), [("msra", 0.5, 0.0), ("gyro", 0.0, 12.0)])
def test_constant_temperature_mean(sensor: str, accel: float, rate: float) -> None:
    density = 0.0024
    spec = ModelSpec(sensor, 10.0, 50.0, (3.0, -8.0, 0.5), (200.0, 1.0, -0.3),
                     {"white_noise": {"density": density}})
    n, fs = 20_000, 10.0
    out = to_sensor_model(spec).simulate(
        profile(np.full(n, 10.0), accel, rate, sensor, fs), np.random.default_rng(1))
    expected = 3.0 + (accel if sensor == "msra" else rate) * 200.0
    sigma = density * np.sqrt(fs)
    assert out.std() == pytest.approx(sigma, rel=0.05)
    assert abs(out.mean() - expected) < 4.0 * sigma / np.sqrt(n)
    # away from the centre the polynomials are evaluated at u = (T - centre) / half_range
    quiet = to_sensor_model(ModelSpec(sensor, 10.0, 50.0, (3.0, -8.0, 0.5), (200.0, 1.0, -0.3)))
    u = 0.5
    out = quiet.simulate(profile(np.full(10, 35.0), accel, rate, sensor), np.random.default_rng(1))
    np.testing.assert_allclose(out, 3.0 - 8.0 * u + 0.5 * u**2 + (accel + rate) * (200.0 + u - 0.3 * u**2))


def test_simulate_recording_with_model() -> None:
    spec = ModelSpec("gyro", 25.0, 50.0, (0.01,), (1.0,), {"white_noise": {"density": 0.001}})
    rec = simulate_recording("gyro", "static", 7, 0, model=to_sensor_model(spec), duration_s=600.0,
                             sample_rate_hz=10.0)
    assert rec.meta.device_id == "fitted-gyro" and rec.meta.extra["device_seed"] == 7
    assert rec.meta.extra["device"]["model"] == "polynomial"
    assert rec.output.mean() == pytest.approx(0.01, abs=4 * 0.001 * np.sqrt(10.0) / np.sqrt(6000))
    with pytest.raises(ValueError, match="for a gyro, not a msra"):
        simulate_recording("msra", "fulltemp", 0, 0, model=to_sensor_model(spec))


def test_thermal_lag_delays_the_output() -> None:
    """A 20 degC step with a linear bias of 1 Hz per 20 degC: without lag the output jumps,
    with ``tau_s`` it reaches 1 - 1/e of the step after ``tau_s``."""
    tau = 300.0
    temp = np.where(np.arange(4000) < 1000, 10.0, 30.0)
    base = ModelSpec("msra", 10.0, 20.0, (0.0, 1.0), (200.0,))
    lagged = ModelSpec("msra", 10.0, 20.0, (0.0, 1.0), (200.0,), {"thermal_lag": {"tau_s": tau}})
    rng = np.random.default_rng(0)
    direct = to_sensor_model(base).simulate(profile(temp), rng)
    slow = to_sensor_model(lagged).simulate(profile(temp), rng)
    assert direct[1001] == pytest.approx(1.0) and direct[999] == pytest.approx(0.0)
    assert slow[1002] < 0.05
    assert slow[1000 + int(tau)] == pytest.approx(1.0 - np.exp(-1.0), abs=0.02)
    assert slow[-1] == pytest.approx(1.0, abs=1e-3)


def _data(**changes: object) -> dict:
    data = {"tcbench_model": 1, "sensor": "msra", "output_unit": "Hz",
            "core": {"kind": "polynomial", "centre_c": 10.0, "half_range_c": 50.0,
                     "bias": [1.0, 2.0], "scale_factor": [200.0]}}
    for key, value in changes.items():
        if key.startswith("core_"):
            core = dict(data["core"])  # type: ignore[arg-type]
            if value is None:
                core.pop(key[5:])
            else:
                core[key[5:]] = value
            data["core"] = core
        else:
            data[key] = value
    return data


@pytest.mark.parametrize(("data", "words"), [
    ([1, 2], "must be a mapping, got list"),
    (None, "must be a mapping, got nothing"),
    (_data(tcbench_model=2), "unsupported tcbench_model version 2; supported: 1"),
    ({k: v for k, v in _data().items() if k != "tcbench_model"}, "missing 'tcbench_model"),
    (_data(sensor="baro"), "unknown sensor 'baro'; known: msra, gyro"),
    (_data(core_centre_c=None), "core.centre_c is missing"),
    (_data(core_half_range_c="wide"), "core.half_range_c must be a number, got 'wide'"),
    (_data(core_half_range_c=0.0), "core.half_range_c must be > 0"),
    (_data(core_half_range_c=-5), "core.half_range_c must be > 0"),
    (_data(core_bias=[]), "core.bias is empty"),
    (_data(core_bias=None), "core.bias is missing"),
    (_data(core_scale_factor=[1.0, "x"]), "core.scale_factor[1] must be a number"),
    (_data(core_bias=[1.0, float("nan")]), "core.bias[1] must be finite"),
    (_data(core_centre_c=float("inf")), "core.centre_c must be finite"),
    (_data(core_kind="spline"), "unsupported core kind 'spline'"),
    (_data(core=[1]), "core is missing or not a mapping"),
    (_data(effects={"foo": {}}), "unknown effect 'foo'; known: accel_nonlinearity, aging_drift, bias_instability"),
    (_data(effects={"warmup": {"amplitude": 1.0, "tau": 5.0}}), "effect 'warmup' has no parameter tau; known: amplitude, tau_s"),
    (_data(effects={"warmup": {"amplitude": float("inf")}}), "effects.warmup.amplitude must be finite"),
    (_data(effects={"warmup": {"amplitude": True}}), "effects.warmup.amplitude must be a number"),
    (_data(effects=[1]), "effects must be a mapping"),
    (_data(extra=1), "unknown key 'extra'"),
])
def test_errors(tmp_path: Path, data: object, words: str) -> None:
    import yaml

    path = tmp_path / "model.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ModelFileError) as info:
        read_model(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and words in message and "\n" not in message


def test_file_errors(tmp_path: Path) -> None:
    with pytest.raises(ModelFileError, match=r"nope\.yaml: no such file"):
        read_model(tmp_path / "nope.yaml")
    bad = tmp_path / "model.yaml"
    bad.write_text("tcbench_model: 1\ncore: {centre_c: 1.0\n")
    with pytest.raises(ModelFileError, match=r"model\.yaml: YAML syntax error at line \d+, column \d+") as info:
        read_model(bad)
    assert "\n" not in str(info.value)
    with pytest.raises(ModelFileError, match="is a directory"):
        read_model(tmp_path)


def test_cli_simulates_a_model_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_model(SPEC, tmp_path / "fit.yaml")
    out = tmp_path / "rec"
    code = main(["simulate", f"model={path}", "protocol=fulltemp", f"out={out}", "metrics=false",
                 "effects.white_noise.density=0", "without=[warmup]", "seed=3"])
    assert code == 0, capsys.readouterr().err
    csv, sidecar = out / "fit-fulltemp-seed3.csv", out / "fit-fulltemp-seed3.json"
    assert csv.exists() and sidecar.exists()
    extra = json.loads(sidecar.read_text())
    text = json.dumps(extra)
    assert "fitted-msra" in text and "polynomial" in text
    device = next(v for v in _walk(extra) if isinstance(v, dict) and v.get("model") == "polynomial")
    assert device["effects"]["white_noise"] == {"density": 0.0} and "warmup" not in device["effects"]


def _walk(value: object) -> list[object]:
    """Every mapping nested in a JSON value (the sidecar's layout is not this test's concern)."""
    found: list[object] = [value]
    if isinstance(value, dict):
        for v in value.values():
            found += _walk(v)
    elif isinstance(value, list):
        for v in value:
            found += _walk(v)
    return found


@pytest.mark.parametrize(("text", "extra_args", "words"), [
    (GOOD.replace("white_noise:", "foo:"), [], "unknown effect 'foo'; known: accel_nonlinearity"),
    (GOOD, ["sensor=gyro"], "the model is for a msra, but sensor=gyro was given"),
    (GOOD, ["effects.warmup.nope=1"], "effect 'warmup' has no parameter nope"),
])
def test_cli_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str,
                    extra_args: list[str], words: str) -> None:
    path = tmp_path / "model.yaml"
    path.write_text(text)
    code = main(["simulate", f"model={path}", f"out={tmp_path / 'rec'}", "metrics=false", *extra_args])
    err = capsys.readouterr().err
    assert code == 2 and words in err and err.count("\n") == 1
    assert not (tmp_path / "rec").exists()


def test_cli_missing_model_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["simulate", f"model={tmp_path / 'none.yaml'}", "metrics=false"])
    err = capsys.readouterr().err
    assert code == 2 and "none.yaml: no such file" in err and err.count("\n") == 1
