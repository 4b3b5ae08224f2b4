"""tcbench diagnose on real logs' gaps, glitches and clips (issue 46).

- A logging gap (or samples given zero weight, a clip's) made the flicker test refuse the record
  ("the Allan deviation needs a record without gaps"): the slow noise it would have named was
  then taken up by open-world terms (a flicker record of 3 h with a 20-min gap named duty_cycle,
  transient and duty_cycle_2 instead of bias_instability), and the kept effects were never
  rechecked with flicker in the noise model. The test now runs inside the segments.
- The residual spectrum of a record with a gap took the Lomb-Scargle periodogram, whose scipy
  implementation builds samples x 3000 arrays (10.4 GiB for a clipped 465 171-sample record).
- Thermometer glitches (0.0 and -40 degC readings) were neither reported nor given zero weight.
"""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_recording
from tcbench.datasets.real import tofupilot_gyro
from tcbench.diagnose.diagnosis import Diagnosis, diagnose
from tcbench.diagnose.report import lomb
from tcbench.diagnose.report.plots import residual_spectrum
from tcbench.diagnose.screens.glitches import find_glitches, repaired
from tcbench.diagnose.select.locate import allan_excess, why_no_allan
from tcbench.sensors.noise import flicker
from tcbench.sensors.recording import Recording, make_recording
from tcbench.sensors.segments import segments


def _cut(t: np.ndarray, gap_s: float) -> np.ndarray:
    """All but ``gap_s`` of ``t`` from 45 % of its span."""
    start = 0.45 * t[-1]
    return ~((t >= start) & (t < start + gap_s))


def _flicker_record(hours: float = 3.0, gap_s: float = 0.0, dt_s: float = 2.0, seed: int = 1,
                    b: float = 0.005) -> Recording:
    """A gyro at rest through heat-and-cool triangles (10..50 degC over 2 h) sampled every
    ``dt_s``: a linear temperature slope, flicker of ``b`` and white noise; ``gap_s`` of it cut
    out at 45 % of the record."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, hours * 3600.0, dt_s)
    temp = 10.0 + 40.0 * np.abs(((t / 3600.0) % 2.0) - 1.0)
    y = 0.02 * (temp - 30.0) + flicker(t.size, dt_s, b, rng) + 0.01 * rng.standard_normal(t.size)
    read = temp + 0.05 * rng.standard_normal(t.size)
    keep = _cut(t, gap_s)
    return make_recording(t[keep], read[keep], np.zeros(int(keep.sum())), y[keep], sensor="gyro",
                          sample_rate_hz=1.0 / dt_s, device_id="gap-test")


@pytest.fixture(scope="module")
def clean() -> tuple[Recording, Diagnosis]:
    """The 3 h flicker record (5400 samples) and its diagnosis: flicker, nothing else."""
    rec = _flicker_record()
    return rec, diagnose(rec)


def test_allan_test_runs_inside_the_segments_of_a_gapped_record() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(20_000.0)
    keep = _cut(t, 1200.0)
    white = rng.standard_normal(t.size)
    assert why_no_allan(t[keep]) is None
    ex = allan_excess(t[keep], white[keep], 1.0, 0.01, estimated=False)
    assert ex is not None and ex.first_over is None  # white noise: nothing flagged
    # taus up to a tenth of the record, as without the gap; the white line is met
    assert ex.tau_s[-1] >= 1000.0 and np.all(np.abs(ex.adev / ex.white - 1.0) < 0.2)
    slow = white + np.cumsum(0.05 * rng.standard_normal(t.size))  # a random walk: flagged with the gap too
    walk = allan_excess(t[keep], slow[keep], 1.0, 0.01, estimated=False)
    assert walk is not None and walk.first_over is not None


def test_the_gap_across_two_segments_is_not_an_allan_term() -> None:
    """A jump between the two sides of a gap (a restart's new bias) is no slow noise: the pooled
    Allan deviation never differences across the gap."""
    rng = np.random.default_rng(4)
    t = np.arange(20_000.0)
    keep = _cut(t, 1200.0)
    r = rng.standard_normal(t.size) + np.where(t > 0.5 * t[-1], 50.0, 0.0)
    ex = allan_excess(t[keep], r[keep], 1.0, 0.01, estimated=False)
    assert ex is not None and ex.first_over is None


def test_burst_too_short_for_the_shortest_tau_is_refused_with_the_reason() -> None:
    t = np.concatenate([k * 600.0 + np.arange(15.0) for k in range(40)])
    assert "longest of this record's 40 segments" in why_no_allan(t)  # type: ignore[operator]


def test_gapped_spectrum_needs_no_samples_by_frequencies_array(monkeypatch: pytest.MonkeyPatch) -> None:
    """A record with a gap is zero-filled on its clock: no Lomb-Scargle; a record of bursts takes
    Lomb-Scargle chunk by chunk, never more than the budget in one call."""
    calls: list[int] = []
    scipy_ls = lomb.lombscargle

    def counted(t: np.ndarray, x: np.ndarray, w: np.ndarray) -> np.ndarray:
        calls.append(t.size * w.size)
        return scipy_ls(t, x, w)

    monkeypatch.setattr(lomb, "lombscargle", counted)
    rng = np.random.default_rng(7)
    fs, sigma, period = 2.0, 0.3, 600.0
    t = np.arange(0.0, 6 * 3600.0, 1.0 / fs)
    keep = _cut(t, 1200.0)
    r = sigma * rng.standard_normal(t.size) + 0.5 * sigma * np.sin(2 * np.pi * t / period)
    f, p, method = residual_spectrum(t[keep], r[keep])
    assert method.startswith("periodogram") and not calls
    assert abs(f[np.argmax(p)] - 1.0 / period) < 0.05 / period
    high = f > 0.05  # white alone: one-sided density 2 sigma^2 / fs, whatever the gap
    assert np.median(p[high]) == pytest.approx(2.0 * sigma**2 / fs * np.log(2.0), rel=0.1)
    bursts = ((t % 300.0) < 60.0) & (t < 3600.0)  # 1440 samples: two chunks of the budget
    f, p, method = residual_spectrum(t[bursts], r[bursts])
    assert method == "Lomb-Scargle" and f.size == 3000 and len(calls) > 1 and max(calls) <= lomb.MAX_ELEMENTS


def test_a_clipped_record_is_a_saturation_finding_with_a_span_sized_spectrum() -> None:
    """The flicker record clipped at its output's 90th percentile (one level everywhere): a
    saturation finding at that level; the clipped samples' zero weight leaves gaps (episodes of
    more than five samples), so the residual's spectrum is zero-filled on the record's clock
    (before: Lomb-Scargle, samples x 3000 arrays, 10.4 GiB on the 516 930-row oven record)."""
    rec = _flicker_record()
    y = rec.output
    level = float(np.percentile(y, 90))
    data = rec.data.copy()
    data["output"] = np.minimum(y, level)
    d = diagnose(Recording(data, rec.meta))
    sat = next(e for e in d.effects if e.id == "saturation")
    assert sat.params["upper"] == pytest.approx(level)
    assert sat.params["clipped"] == pytest.approx(int((y >= level).sum()), abs=3)  # within the level's tolerance
    t = np.asarray(d.series.t_s)
    assert segments(t)[-1] > 0 and residual_spectrum(t, d.series.residual_after)[2].startswith("periodogram")


def test_chunked_lomb_scargle_gives_scipy_numbers() -> None:
    rng = np.random.default_rng(2)
    t = np.sort(rng.uniform(0.0, 1000.0, 500))
    x = rng.standard_normal(500)
    w = np.linspace(0.01, 3.0, 97)
    assert np.allclose(lomb.lombscargle_chunked(t, x, w, max_elements=500 * 10), lomb.lombscargle(t, x, w),
                       rtol=1e-12, atol=0.0)


def test_a_logging_gap_changes_no_finding(clean: tuple[Recording, Diagnosis]) -> None:
    """20 min cut out of the 3 h flicker record: the same effects named, flicker tested on both
    (before, the gapped record named nothing: its flicker test was refused)."""
    gapped = diagnose(_flicker_record(gap_s=1200.0))
    assert clean[1].effect_ids == ["bias_instability"]
    assert gapped.effect_ids == clean[1].effect_ids
    assert "bias_instability" not in gapped.statistics.not_tested


def _glitched(rec: Recording, index: np.ndarray, values: list[float]) -> Recording:
    data = rec.data.copy()
    temp = data["temperature_c"].to_numpy(dtype=float).copy()
    temp[index] = values
    data["temperature_c"] = temp
    return Recording(data, rec.meta)


GLITCHES_C = [0.0, 0.0, 0.0, 0.0, 0.0, -40.0]


def test_thermometer_glitches_are_found_with_their_times_and_values() -> None:
    rec = _flicker_record(1.0, dt_s=1.0)
    t, temp = rec.time_s, rec.temperature_c
    assert find_glitches(t, temp).count == 0
    index = np.array([5, 400, 1200, 1201, 2500, 3599])  # the first and last readings, a run of two
    found = find_glitches(t, _glitched(rec, index, GLITCHES_C).temperature_c)
    assert found.index.tolist() == index.tolist()
    assert found.reading_c.tolist() == GLITCHES_C
    assert np.allclose(found.level_c, temp[index], atol=0.5)
    finding = found.finding().to_json()
    assert finding["params"]["count"] == 6 and finding["where"]["time_s"] == t[index].tolist()
    assert "-40 degC at 3599 s" in finding["explanation"]


def test_no_glitch_on_the_concealed_controls_or_the_real_records() -> None:
    """The concealed thermometers read on a 0.0625 degC lattice with noise about half a step: a
    reading three steps off its neighbours' median is their noise, not a glitch (7 of 60 gyro
    controls showed one when the scale was half the step; 0 of 400 with the lattice's RMS)."""
    for seed in range(30):
        rec, _ = concealed_recording("gyro", None, seed)
        assert find_glitches(rec.time_s, rec.temperature_c).count == 0, seed
    rec = tofupilot_gyro("x")  # a clean real chamber cycle whose cooling turns sharply at its end
    assert find_glitches(rec.time_s, rec.temperature_c).count == 0


def test_a_ramp_or_a_corner_is_not_a_glitch() -> None:
    t = np.arange(3000.0)
    v_corner = 30.0 - 0.05 * np.abs(t - 1500.0)  # a sharp turn at 3 degC/min, no noise
    staircase = np.round((20.0 + 10.0 * np.sin(t / 300.0)) / 0.0625) * 0.0625
    for temp in (v_corner, staircase, 20.0 + 0.02 * t):
        assert find_glitches(t, temp).count == 0


def test_repaired_holds_the_previous_reading() -> None:
    rec = _flicker_record(1.0, dt_s=1.0)
    temp = rec.temperature_c
    fixed = repaired(_glitched(rec, np.array([0, 10, 11]), [0.0, 0.0, -40.0]), np.array([0, 10, 11])).temperature_c
    assert fixed[0] == temp[1] and fixed[10] == fixed[11] == temp[9]
    assert np.array_equal(np.delete(fixed, [0, 10, 11]), np.delete(temp, [0, 10, 11]))


def test_thermometer_glitches_get_zero_weight_and_are_reported(clean: tuple[Recording, Diagnosis]) -> None:
    rec, diagnosed = clean
    n = rec.time_s.size
    index = np.linspace(0.1 * n, 0.9 * n, 6).astype(int)
    glitched = diagnose(_glitched(rec, index, GLITCHES_C))
    ids = [e for e in glitched.effect_ids if e != "thermometer_glitches"]
    assert ids == diagnosed.effect_ids
    clean = diagnosed
    assert glitched.effect_ids.count("thermometer_glitches") == 1
    report = glitched.to_json()
    entry = next(e for e in report["effects"] if e["id"] == "thermometer_glitches")
    assert entry["params"]["count"] == 6 and sorted(entry["params"]["reading_c"]) == sorted(GLITCHES_C)
    assert "6 thermometer glitch(es) given zero weight" in report["verdict"]
    assert glitched.noise.samples == clean.noise.samples - 6
    assert glitched.noise.thermometer_sigma_c == pytest.approx(clean.noise.thermometer_sigma_c, rel=0.05)


def test_a_few_samples_between_two_gaps_are_smoothed_across_their_own_gaps() -> None:
    """A continuous 1 Hz oven record (60 degC down to -40 and back every 3 h) with three short holes, as
    dropped bins leave them around a clip: 8 samples stand between two holes of 30 and 20 s. Their
    smoothed temperature follows the ramp, and the thermometer noise read from the spread about it
    is the reading's own (the record's mean segment spacing, 5 h, made it a line over 15 h that
    missed the ramp by degrees: 0.2 degC of thermometer noise read where 0.02 was put in)."""
    from tcbench.diagnose.select.design import Designer
    from tcbench.diagnose.select.thermometer_noise import thermometer_sigma
    from tcbench.diagnose.signals import prepare, smooth_temperature

    rng = np.random.default_rng(12)
    t = np.arange(0.0, 6 * 3600.0)
    true = 10.0 + 50.0 * (2.0 * np.abs((t / 10800.0) % 1.0 - 0.5) * 2.0 - 1.0)  # -40..60 degC, 3 h period
    keep = ~(((t >= 3000) & (t < 3030)) | ((t >= 3038) & (t < 3058)) | ((t >= 15000) & (t < 15100)))
    t, true = t[keep], true[keep]
    reading = true + rng.normal(0.0, 0.02, t.size)
    fragment = (t >= 3030) & (t < 3038)
    assert np.count_nonzero(fragment) == 8 and np.unique(segments(t)).size == 4
    value, rate = smooth_temperature(t, reading, 120.0)
    assert np.max(np.abs(value[fragment] - true[fragment])) < 0.1
    assert np.max(np.abs(rate[fragment] + 100.0 / 5400.0)) < 0.2 * 100.0 / 5400.0  # cooling at 1.1 degC/min
    rec = make_recording(t, reading, np.zeros(t.size), 0.01 * true + rng.normal(0.0, 0.01, t.size),
                         sensor="gyro", sample_rate_hz=1.0, device_id="clip")
    assert thermometer_sigma(Designer(prepare(rec, smooth_s=120.0))) == pytest.approx(0.02, rel=0.1)
