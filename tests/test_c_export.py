"""The fitted offset models exported as C (:mod:`tcbench.compensation.c_export`), compiled with the
system C compiler and run sample by sample over the real tofupilot and PAN records and a simulated
record of each sensor kind: they give Python's compensated output to 1e-9 (double build) and 1e-4
(float build), relative to the larger of the output and the record's largest raw reading."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import PAN_CSV

from tcbench.compensation.c_export import (c_sources, device_clock_s, device_spec, streamed_corrected, streamed_offset,
                                           window_samples, write_c)
from tcbench.compensation.calibration import OffsetModel, fit, from_model, record
from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.compensation.fitted_model import deterministic_output
from tcbench.sensors.effects import EFFECTS
from tcbench.sensors.fitted import PolynomialModel
from tcbench.datasets.real import tofupilot_gyro
from tcbench.sensors.simulate import simulate_recording

CC = shutil.which("cc")
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
TOLERANCE = {"double": 1e-9, "float": 1e-4}
FIT_ROWS = 1000  # fitted on the first cooling's first 1000 samples (500 s: 100 bins, a fast fit)

HOST = r"""
#include <stdio.h>
#include <stdlib.h>
#include "NAME.h"

/* Reads "temperature raw dt" per line (hexadecimal floats) on stdin, writes each corrected value. */
int main(void)
{
    NAME_state s;
    char line[256];
    NAME_init(&s);
    while (fgets(line, sizeof line, stdin)) {
        char *p = line;
        double temperature = strtod(p, &p), raw = strtod(p, &p), dt = strtod(p, &p);
        printf("%a\n", (double)NAME_update(&s, (NAME_real)temperature, (NAME_real)raw, (NAME_real)dt));
    }
#ifdef UPNAME_RATE_CAPACITY
    fprintf(stderr, "dropped %d\n", s.dropped);
#endif
    fprintf(stderr, "state %u\n", (unsigned)sizeof s);
    return 0;
}
"""


def _records() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Time (s), thermometer (degC) and raw reading of every record the compiled code runs on."""
    out = {}
    gyro = tofupilot_gyro("x")
    out["tofupilot gyro x"] = (gyro.time_s, gyro.temperature_c, gyro.output)
    rate = np.abs(np.gradient(gyro.temperature_c, gyro.time_s))
    mid = int(np.argmax(np.convolve(rate, np.ones(101) / 101, "same")))  # the steepest ramp
    out["tofupilot, from mid-ramp"] = (gyro.time_s[mid:] - gyro.time_s[mid], gyro.temperature_c[mid:], gyro.output[mid:])
    keep = np.r_[np.arange(0, 4000), np.arange(4000, gyro.time_s.size, 3)]  # the interval triples half way
    out["tofupilot, interval 0.5 then 1.5 s"] = (gyro.time_s[keep], gyro.temperature_c[keep], gyro.output[keep])
    pan = pd.read_csv(PAN_CSV)
    pan = pan[pan["spike_flag"] == 0]
    for a in "xyz":  # bursts of 20-ms samples every 300 s
        out[f"PAN gyro {a}"] = (pan["time_s"].to_numpy(np.float64), pan["temp_c"].to_numpy(np.float64),
                                pan[f"gyro_{a}_dps"].to_numpy(np.float64))
    for kind, protocol in (("gyro", "oven"), ("accel", "chamber"), ("msra", "fulltemp")):
        rec = simulate_recording(kind, protocol, 0, 0)
        n = min(rec.time_s.size, 12_000)  # 20 min of the gyro at 10 Hz
        out[f"simulated {kind}"] = (rec.time_s[:n], rec.temperature_c[:n], rec.output[:n])
    return out


@pytest.fixture(scope="module")
def records() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return _records()


@pytest.fixture(scope="module")
def models() -> dict[str, OffsetModel]:
    """Every exported method fitted on the start of the tofupilot gyro x's first cooling, as
    calibrate fits it (``bp`` by gradient descent: too few bins for LM)."""
    gyro = tofupilot_gyro("x")
    whole = record(gyro.time_s, gyro.temperature_c, gyro.output, gyro.input)
    part = whole.part(0, FIT_ROWS)
    return {m: fit(m, [part], seed=0) for m in ("poly3", "poly3_rate", "bp", "elman")} | {"model": from_model(diagnosed())}


def diagnosed() -> PolynomialModel:
    """A diagnosed gyro model with every term the export runs (near the tofupilot gyro x's own
    diagnosis: its core, hysteresis and bump), a warm-up and a line its compensator leaves out."""
    e = EFFECTS
    return PolynomialModel(sensor="gyro", centre_c=28.18, half_range_c=45.78, bias=(-4.128, 0.2612, 0.8546), ref_c=28.18,
                           effects=(e["warmup"](amplitude=0.5, tau_s=300.0), e["thermal_lag"](tau_s=120.0),
                                    e["temperature_rate"](coef_per_c_per_s=3.0),
                                    e["hysteresis"](amplitude=-0.164, width_c=18.47, start_state=0.5),
                                    e["temperature_cubic"](c3_per_c3=2e-6),
                                    e["temperature_bump"](centre_c=10.34, width_c=1.5, amplitude=0.0352),
                                    e["second_node"](tau_s=900.0, coef_per_c=0.01),
                                    e["periodic"](period_s=661.0, amplitude=0.0225, phase_rad=0.55)))


def _fullest(records: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]) -> int:
    return max(window_samples(t) for t, _, _ in records.values())


@pytest.fixture(scope="module")
def programs(models: dict[str, OffsetModel], records: dict, tmp_path_factory: pytest.TempPathFactory
             ) -> dict[tuple[str, str], tuple[Path, dict]]:
    """Each model's C compiled in both builds with the host program: ``(method, build)`` -> the
    program and its spec."""
    folder = tmp_path_factory.mktemp("c")
    out = {}
    for method, model in models.items():
        spec = device_spec(model, _fullest(records))
        name = f"tc_gyro_x_{method}"
        write_c(spec, name, folder)
        (folder / f"{name}_host.c").write_text(HOST.replace("UPNAME", name.upper()).replace("NAME", name))
        for build in ("double", "float"):
            exe = folder / f"{name}_{build}"
            flags = [f"-D{name.upper()}_FLOAT"] if build == "float" else []
            done = subprocess.run([CC, "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror", *flags,
                                   str(folder / f"{name}_host.c"), str(folder / f"{name}.c"), "-lm", "-o", str(exe)],
                                  capture_output=True, text=True)
            assert done.returncode == 0, done.stderr
            out[(method, build)] = (exe, spec)
    return out


def _run(exe: Path, temp_c: np.ndarray, raw: np.ndarray, dt_s: np.ndarray) -> tuple[np.ndarray, dict[str, int]]:
    lines = "".join(f"{a.hex()} {b.hex()} {c.hex()}\n" for a, b, c in zip(temp_c.tolist(), raw.tolist(), dt_s.tolist()))
    done = subprocess.run([str(exe)], input=lines, capture_output=True, text=True, check=True)
    said = dict((k, int(v)) for k, v in (ln.split() for ln in done.stderr.splitlines()))
    return np.array([float.fromhex(v) for v in done.stdout.split()]), said


def _as_fed(values: np.ndarray, build: str) -> np.ndarray:
    """The values as the build receives them (a float build rounds them to float)."""
    return values.astype(np.float32).astype(np.float64) if build == "float" else values


@pytest.fixture(scope="module")
def rates() -> dict[tuple[str, str], np.ndarray]:
    """The reference rate of each record as each build is fed (computed once)."""
    return {}


EPSILON = {"double": 2.0 ** -52, "float": 2.0 ** -23}


def _stable(spec: dict, clock: np.ndarray, temp_c: np.ndarray, rate: np.ndarray, bound: np.ndarray,
            build: str) -> np.ndarray:
    """The samples before the reference first moves by a tenth of ``bound`` when its temperatures
    or its rates move by the build's rounding (one part in 2^52 or 2^23). The Elman fitted on 100
    bins expands its context far outside its training (W_c's largest singular value is about 3.5):
    a rounding difference there grows tenfold every ~100 s, so after that point no two correct
    implementations (numpy's order of operations, the C's) agree to the tolerance."""
    ref = streamed_offset(spec, clock, temp_c, rate)
    eps = EPSILON[build]
    moved = np.maximum(np.abs(streamed_offset(spec, clock, temp_c * (1 + eps), rate) - ref),
                       np.abs(streamed_offset(spec, clock, temp_c, rate * (1 + eps)) - ref))
    beyond = np.flatnonzero(10.0 * moved > bound)
    return np.arange(clock.size) < (beyond[0] if beyond.size else clock.size)


@pytest.mark.parametrize("build", ["double", "float"])
@pytest.mark.parametrize("method", ["poly3", "poly3_rate", "bp", "elman", "model"])
def test_the_compiled_model_gives_pythons_output_on_every_record(programs: dict, records: dict, rates: dict,
                                                                 method: str, build: str) -> None:
    exe, spec = programs[(method, build)]
    for label, (t_s, temp_c, raw) in records.items():
        dt_s = np.r_[0.0, np.diff(t_s)]
        fed_temp, fed_raw, fed_dt = (_as_fed(v, build) for v in (temp_c, raw, dt_s))
        got, said = _run(exe, temp_c, raw, dt_s)
        assert got.size == t_s.size, label
        assert said.get("dropped", 0) == 0, f"{label}: the rate ring overflowed"
        clock = device_clock_s(fed_dt)
        if method != "poly3" and (label, build) not in rates:
            rates[(label, build)] = temperature_rate_c_per_s(clock, fed_temp)
        rate = rates.get((label, build))
        want = fed_raw - streamed_offset(spec, clock, fed_temp, rate)
        bound = TOLERANCE[build] * np.maximum(np.abs(want), np.max(np.abs(raw)))
        keep = np.ones(t_s.size, dtype=bool)
        if "wc" in spec:  # up to where the reference's own rounding has grown to the tolerance (_stable)
            keep = _stable(spec, clock, fed_temp, rate, bound, build)
            assert np.mean(keep) > 0.8, label
        worst = int(np.argmax(np.where(keep, np.abs(got - want) / bound, 0.0)))
        assert np.all(np.abs(got - want)[keep] <= bound[keep]), (label, worst, got[worst], want[worst])
        assert np.ptp(want - fed_raw) > 0, label  # the model corrects something there


def test_the_stated_state_size_is_the_compiled_one(programs: dict, records: dict) -> None:
    t_s, temp_c, raw = records["PAN gyro x"]
    for (method, build), (exe, spec) in programs.items():
        _, said = _run(exe, temp_c[:3], raw[:3], np.r_[0.0, np.diff(t_s[:3])])
        stated = c_sources(spec, f"tc_gyro_x_{method}").state_bytes[build]
        assert said["state"] == stated, (method, build)
        assert f"{stated} bytes ({build} build)" in c_sources(spec, "x").header


def test_the_reference_is_what_calibrate_scores(models: dict[str, OffsetModel], records: dict) -> None:
    """The numpy reference the C is checked against is calibrate's own offset: the cubics and bp to
    rounding on the record's clock; the Elman, stepped per bin, gives calibrate's bin values at each
    bin's last sample (calibrate interpolates between them, reading ahead; the device cannot)."""
    t_s, temp_c, raw = records["tofupilot gyro x"]
    rec = record(t_s, temp_c, raw, np.zeros_like(raw))
    for method in ("poly3", "poly3_rate", "bp"):
        spec = device_spec(models[method], window_samples(t_s))
        ref = models[method].offset(rec)
        np.testing.assert_allclose(streamed_offset(spec, t_s - t_s[0], temp_c), ref, rtol=0,
                                   atol=1e-10 * np.max(np.abs(ref)))
    elman = models["elman"]
    spec = device_spec(elman, window_samples(t_s))
    streamed = streamed_offset(spec, t_s - t_s[0], temp_c)
    binned = rec.binned(spec["bin_s"])
    on_bins = elman.learner.predict(np.column_stack([np.clip(binned.temp_c, *elman.temp_range_c),
                                                     np.clip(binned.rate_c_per_s, *elman.rate_range)]))
    index = np.floor((t_s - t_s[0]) / spec["bin_s"]).astype(np.int64)
    last = np.flatnonzero(np.r_[index[1:] != index[:-1], True])
    np.testing.assert_allclose(streamed[last], on_bins, rtol=1e-9, atol=1e-9 * np.max(np.abs(on_bins)))
    assert not np.allclose(streamed, elman.offset(rec), atol=1e-3)  # the look-ahead differs elsewhere


def test_the_streamed_model_is_the_diagnosed_one(models: dict[str, OffsetModel], records: dict) -> None:
    """The device's diagnosed model (per sample: play operator at every sample, the lags on the
    device's own intervals) is calibrate's compensator (uniform grid, 1-Hz play operator) on the
    tofupilot record to 2e-4 of the offset's span, and leaves out the warm-up and the line as it
    does. The rate term is left out of the comparison: the device's backward difference reads the
    thermometer's steps (about 0.01 degC every 0.5 s) where calibrate's central difference on its
    grid averages it, by 0.05 deg/s RMS with this model's 3 deg/s per degC/s."""
    t_s, temp_c, raw = records["tofupilot gyro x"]
    spec = device_spec(models["model"], window_samples(t_s))
    assert [e["id"] for e in spec["effects"]] == ["thermal_lag", "temperature_rate", "hysteresis", "temperature_cubic",
                                                  "temperature_bump", "second_node"]
    no_rate = diagnosed().without("temperature_rate")
    streamed = streamed_offset(device_spec(from_model(no_rate), 10), t_s - t_s[0], temp_c)
    scored = deterministic_output(no_rate, t_s, temp_c, np.zeros_like(t_s), clock_terms=False)
    assert np.max(np.abs(streamed - scored)) < 2e-4 * np.ptp(scored)
    apart = streamed_offset(spec, t_s - t_s[0], temp_c) - deterministic_output(diagnosed(), t_s, temp_c,
                                                                              np.zeros_like(t_s), clock_terms=False)
    assert 0.02 < np.sqrt(np.mean(apart ** 2)) < 0.1


def test_a_model_with_a_term_no_device_runs_is_refused() -> None:
    model = PolynomialModel(sensor="gyro", bias=(0.1, 0.2), effects=(EFFECTS["saturation"](upper=10.0),))
    with pytest.raises(ValueError, match="its saturation term is not exported as C"):
        device_spec(from_model(model), 10)


def test_a_ring_too_small_is_counted(models: dict[str, OffsetModel], records: dict, tmp_path: Path) -> None:
    """A record sampled faster than the calibration's: the rate ring overflows and says so."""
    t_s, temp_c, raw = records["tofupilot gyro x"]
    spec = device_spec(models["poly3_rate"], 10)
    write_c(spec, "small", tmp_path)
    (tmp_path / "host.c").write_text(HOST.replace("UPNAME", "SMALL").replace("NAME", "small"))
    subprocess.run([CC, "-std=c99", str(tmp_path / "host.c"), str(tmp_path / "small.c"), "-lm", "-o",
                    str(tmp_path / "small")], check=True)
    _, said = _run(tmp_path / "small", temp_c[:500], raw[:500], np.r_[0.0, np.diff(t_s[:500])])
    assert said["dropped"] > 0 and spec["rate_capacity"] == 15


def test_names_and_methods_no_device_runs_are_refused() -> None:
    with pytest.raises(ValueError, match="not a C identifier"):
        c_sources({"method": "poly3", "x": [0, 0, 0, 0], "tref_c": 0, "tmin_c": 0, "tmax_c": 1}, "9lives")
    with pytest.raises(ValueError, match="memoriser: a control"):
        device_spec(OffsetModel("memoriser"), 10)


def test_a_model_with_a_scale_factor_returns_the_input(records: dict, tmp_path: Path) -> None:
    """A diagnosis of a record with several input levels has a scale factor in the die temperature
    (``bias(u) + a s(u)``): its C returns ``(raw - offset) / s(u)``, the input that explains the
    reading. Compiled, it gives :func:`streamed_corrected` to the tolerance in both builds, and on
    the model's own output for a slow swing of rates over the tofupilot thermometer it returns
    those rates to 1e-3 of their span (``raw - offset`` alone misses them by the scale factor's
    2 %; the die lag runs per sample on the device, on calibrate's grid in the model)."""
    t_s, temp_c, _ = records["tofupilot gyro x"]
    model = PolynomialModel(sensor="gyro", centre_c=28.18, half_range_c=45.78, bias=(-4.128, 0.2612, 0.8546),
                            scale_factor=(1.02, 0.015, -0.004), ref_c=28.18,
                            effects=(EFFECTS["thermal_lag"](tau_s=120.0),
                                     EFFECTS["temperature_cubic"](c3_per_c3=2e-6)))
    rates = 50.0 * np.sin(2 * np.pi * t_s / 900.0)  # deg/s, a slow swing through the cycle
    raw = deterministic_output(model, t_s, temp_c, rates, clock_terms=False)
    spec = device_spec(from_model(model), 10)
    assert spec["scale_factor"] == [1.02, 0.015, -0.004]
    clock = t_s - t_s[0]
    corrected = streamed_corrected(spec, clock, temp_c, raw)
    assert np.max(np.abs(corrected - rates)) < 1e-3 * np.ptp(rates)
    assert np.max(np.abs(raw - streamed_offset(spec, clock, temp_c) - rates)) > 1e-2 * np.ptp(rates)
    write_c(spec, "scaled", tmp_path)
    (tmp_path / "host.c").write_text(HOST.replace("UPNAME", "SCALED").replace("NAME", "scaled"))
    dt_s = np.r_[0.0, np.diff(t_s)]
    for build in ("double", "float"):
        flags = ["-DSCALED_FLOAT"] if build == "float" else []
        subprocess.run([CC, "-std=c99", "-O2", *flags, str(tmp_path / "host.c"), str(tmp_path / "scaled.c"), "-lm",
                        "-o", str(tmp_path / build)], check=True)
        got, _ = _run(tmp_path / build, temp_c, raw, dt_s)
        fed_temp, fed_raw, fed_dt = (_as_fed(v, build) for v in (temp_c, raw, dt_s))
        want = streamed_corrected(spec, device_clock_s(fed_dt), fed_temp, fed_raw)
        bound = TOLERANCE[build] * np.maximum(np.abs(want), np.max(np.abs(raw)))
        assert np.all(np.abs(got - want) <= bound), build
