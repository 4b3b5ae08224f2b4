"""The report contract for every finding (tcbench.diagnose.findings, library_findings) and how
report.md and the plots show it (markdown.finding_section, plots.mark_*).

The recording: the concealed gyro with a hidden thermal lag (seed 2, 8.7 h at 1 Hz), plus a
warm-up of 20 white sigma decaying with 900 s from power-on and two spikes (+60 and -80 sigma at
t = 5000 s and 17000 s). The diagnosis names thermal_lag and warmup (library) and the two
outliers (not library).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import Diagnosis, Series, diagnose
from tcbench.diagnose.findings import SHAPES, Finding, check_finding
from tcbench.diagnose.report.explain import explain
from tcbench.diagnose.report.markdown import finding_section, format_where, render_markdown
from tcbench.diagnose.report.plots import mark_bands, mark_levels, mark_times, residual_spectrum, write_plots
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.select.library_findings import Extent, library_finding
from tcbench.diagnose.terms import confusable_pairs, terms
from tcbench.sensors.recording import Recording

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
# docs/concepts/diagnosis-report.md, shapes: the shape each library effect takes in a residual (a
# literal guard on the terms' shapes; test_the_shapes_cover_the_registry checks it lists every term)
EXPECTED_SHAPE = {
    "thermal_lag": "temperature_dynamics", "temperature_rate": "temperature_dynamics",
    "hysteresis": "temperature_dynamics", "temperature_cubic": "temperature_function", "warmup": "transient",
    "aging_drift": "trend", "accel_nonlinearity": "input_function", "bias_instability": "noise",
}
PARAMS = {
    "thermal_lag": {"tau_s": 600.0}, "temperature_rate": {"coef_per_c_per_s": 0.5},
    "hysteresis": {"amplitude": 0.01, "width_c": 3.0}, "temperature_cubic": {"c3_per_c3": 1e-6},
    "warmup": {"amplitude": 0.02, "tau_s": 900.0}, "aging_drift": {"rate_per_h": 1e-4},
    "accel_nonlinearity": {"k2_per_g2": -0.3}, "bias_instability": {"b": 0.001},
}
EXTENT = Extent(t_start_s=0.0, t_end_s=36_000.0, temp_low_c=-10.0, temp_high_c=60.0, unit="deg/s")


@pytest.fixture(scope="module")
def several() -> Diagnosis:
    rec, truth = concealed_recording("gyro", "thermal_lag", 2)
    s = truth.white_sigma
    data = rec.data.copy()
    out = data["output"].to_numpy(dtype=float).copy()
    out += 20.0 * s * np.exp(-rec.time_s / 900.0)
    out[[5000, 17000]] += [60.0 * s, -80.0 * s]
    data["output"] = out
    return diagnose(Recording(data, rec.meta), name="gyro-lag-warmup-spikes")


@pytest.fixture(scope="module")
def written(several: Diagnosis, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], str, Path]:
    out = tmp_path_factory.mktemp("report")
    write_report(several, out)
    return json.loads((out / "report.json").read_text()), (out / "report.md").read_text(), out


def test_every_effect_in_report_json_satisfies_the_contract(written: tuple[dict[str, Any], str, Path]) -> None:
    report, _, _ = written
    ids = [e["id"] for e in report["effects"]]
    assert {"thermal_lag", "warmup", "outliers"} <= set(ids), report["verdict"]
    for entry in report["effects"]:
        check_finding(entry)
        assert entry["library"] is (entry["id"] in {t.id for t in terms()})
        if entry["library"]:
            assert entry["shape"] == EXPECTED_SHAPE[entry["id"]]
    by_id = {e["id"]: e for e in report["effects"]}
    low, high = by_id["thermal_lag"]["where"]["temperature_c"]
    assert 10.0 < low < 15.0 and 45.0 < high < 52.0  # the recording's band, 12.8 to 49.5 degC
    assert by_id["warmup"]["where"] == {"time_s": 0.0}
    assert by_id["outliers"]["where"]["time_s"] == [pytest.approx(5000.0), pytest.approx(17000.0)]
    assert by_id["thermal_lag"]["explanation"].startswith("The output follows a temperature that trails")


def test_the_shapes_cover_the_registry() -> None:
    assert set(EXPECTED_SHAPE) == set(PARAMS) == {t.id for t in terms()}


@pytest.mark.parametrize("effect", [t.id for t in terms()])
def test_each_library_effect_maps_to_its_shape(effect: str) -> None:
    f = library_finding(effect, PARAMS[effect], {"gain_sigma2": 50.0}, EXTENT).to_json()
    check_finding(f)
    assert f["shape"] == EXPECTED_SHAPE[effect] and f["shape"] in SHAPES and f["library"] is True
    assert f["explanation"] == explain(effect, PARAMS[effect], "deg/s")
    assert f["confirm_with"] and "confusable_with" not in f
    if EXPECTED_SHAPE[effect].startswith("temperature_"):
        assert f["where"] == {"temperature_c": [-10.0, 60.0]}
    elif effect == "warmup":
        assert f["where"] == {"time_s": 0.0}
    else:
        assert f["where"] == {}


def test_report_md_gives_each_parameter_its_terms_unit() -> None:
    """The parameters of a library finding carry the units its term declares; a screen's finding
    (no term) those the report knows for it."""
    lines = {e: finding_section(library_finding(e, PARAMS[e], {}, EXTENT), "deg/s", 0.0)[3] for e in PARAMS}
    assert lines["temperature_rate"] == "- Parameters: coef_per_c_per_s = 0.5 deg/s per degC/s"
    assert lines["hysteresis"] == "- Parameters: amplitude = 0.01 deg/s; width_c = 3 degC"
    assert lines["aging_drift"] == "- Parameters: rate_per_h = 0.0001 deg/s/h"
    assert lines["bias_instability"] == "- Parameters: b = 0.001 deg/s (flicker coefficient)"
    assert lines["thermal_lag"] == "- Parameters: tau_s = 600 s (10 min)"
    screen = Finding("variance", "variance", False, {"density": 0.2, "b": 3.0}, {}, {}, "x", "y")
    assert finding_section(screen, "g", 0.0)[3] == "- Parameters: density = 0.2 g/sqrt(Hz); b = 3"


def test_confusable_effect_names_the_test_that_separates_it() -> None:
    f = library_finding("thermal_lag", PARAMS["thermal_lag"], {}, EXTENT, ["temperature_rate", "hysteresis"]).to_json()
    assert f["confusable_with"] == ["temperature_rate", "hysteresis"]
    for other in ("temperature_rate", "hysteresis"):
        assert confusable_pairs()[frozenset({"thermal_lag", other})] in f["confirm_with"]
    with pytest.raises(ValueError, match="not an effect of the library"):
        library_finding("bias_step", {}, {}, EXTENT)


def test_report_md_shows_where_explanation_and_confirm_with(written: tuple[dict[str, Any], str, Path],
                                                            several: Diagnosis) -> None:
    report, md, _ = written
    t0 = float(several.series.t_s[0])
    for f in report["effects"]:
        kind = "library effect" if f["library"] else "not a library effect"
        assert f"### {f['id']} ({f['shape']}, {kind})" in md
        assert f"- Where: {format_where(f['where'], f['params'].get('unit', report['unit']), t0)}" in md
        assert f"- Confirm with: {f['confirm_with']}" in md
        assert f["explanation"] in md
    assert "temperature band 12.84 to 49.45 degC" in md
    assert "at t = 5000 s (1.389 h from the start), 17000 s (4.722 h from the start)" in md
    assert "| thermal_lag | temperature_dynamics | yes |" in md and "| outliers | outliers | no |" in md


def test_every_finding_reads_back_from_its_report_entry(written: tuple[dict[str, Any], str, Path],
                                                        several: Diagnosis) -> None:
    report, _, _ = written
    assert [f.id for f in several.effects] == [e["id"] for e in report["effects"]]
    for entry in report["effects"]:
        assert Finding.from_json(entry).to_json() == entry


def _open_world() -> list[dict[str, Any]]:
    """Findings of shapes outside the library, as the open-world detectors write them."""
    base = {"library": False, "evidence": {"gain_sigma2": 40.0, "threshold_sigma2": 10.0, "test": "permutation"},
            "explanation": "a cause in plain words", "confirm_with": "a measurement"}
    return [
        base | {"id": "bias_step", "shape": "step", "params": {"jump": 0.01}, "where": {"time_s": 7200.0}},
        base | {"id": "chamber_line", "shape": "periodic", "params": {"amplitude": 0.002},
                "where": {"period_s": 1200.0, "frequency_hz": 1.0 / 1200.0}},
        base | {"id": "clip", "shape": "saturation", "params": {"ceiling": 0.5},
                "where": {"level": [0.5], "temperature_c": [20.0, 30.0]}},
        base | {"id": "thermometer_grid", "shape": "quantisation", "params": {"step_c": 1.0, "unit": "degC"},
                "where": {"level": 1.0}},
    ]


def test_markdown_renders_open_world_findings_without_knowing_their_ids(several: Diagnosis) -> None:
    findings = _open_world()
    for f in findings:
        check_finding(f)
    md = render_markdown(replace(several, effects=[Finding.from_json(f) for f in findings]), {})
    for f in findings:
        assert f"### {f['id']} ({f['shape']}, not a library effect)" in md
    t0 = float(several.series.t_s[0])
    assert f"at t = 7200 s ({(7200.0 - t0) / 3600.0:.4g} h from the start)" in md
    assert "period 1200 s (20 min); frequency 0.0008333 Hz (period 20 min)" in md
    assert "level 0.5 deg/s; " not in md and "temperature band 20 to 30 degC; level 0.5 deg/s" in md
    assert "level 1 degC" in md  # a thermometer level in the finding's own unit
    assert "test: permutation" in md


@dataclass
class _WithOutput(Series):
    """A series that also carries the output (for the output plot and its level lines)."""

    output: np.ndarray | None = None


@pytest.mark.figures
def test_plots_mark_every_located_finding(several: Diagnosis, tmp_path: Path) -> None:
    s = several.series
    series = _WithOutput(s.t_s, s.temp_c, s.residual_before, s.residual_after, s.allan_before, s.allan_after,
                         output=np.asarray(s.residual_before) + 0.1)
    d = replace(several, effects=[*several.effects, *map(Finding.from_json, _open_world())], series=series)
    t0, t1 = float(s.t_s[0]), float(s.t_s[-1])
    fig, ax = plt.subplots()
    # warm-up at 0, two outliers, the step at 7200 s
    assert mark_times(ax, d, t0, t1) == 4
    xs = sorted(float(line.get_xdata()[0]) for line in ax.lines)
    assert xs == pytest.approx(sorted((t - t0) / 3600.0 for t in (0.0, 5000.0, 17000.0, 7200.0)))
    # thermal_lag's band (the recording's range: strip only) and the clip's band (strip and shading)
    assert mark_bands(ax, d, (float(np.min(s.temp_c)), float(np.max(s.temp_c)))) == 2
    assert len(ax.patches) == 3
    assert mark_levels(ax, d, "deg/s") == 1 and mark_levels(ax, d, "degC") == 1
    plt.close(fig)
    files = write_plots(d, tmp_path)
    assert set(files) == {"residuals", "allan", "evidence", "spectrum", "output"}
    for name in files.values():
        data = (tmp_path / name).read_bytes()
        assert data[:8] == PNG_MAGIC and 10_000 < len(data) < 1_500_000


def test_no_output_plot_without_the_output(several: Diagnosis, tmp_path: Path) -> None:
    assert "output" not in write_plots(several, tmp_path)
    assert not (tmp_path / "output.png").exists()


@pytest.mark.parametrize("bursts", [False, True])
def test_residual_spectrum_finds_a_line_at_the_white_level(bursts: bool) -> None:
    rng = np.random.default_rng(7)
    fs, sigma, period = 2.0, 0.3, 600.0
    t = np.arange(0.0, 6 * 3600.0, 1.0 / fs)
    if bursts:  # 60 s of every 300 s
        t = t[(t % 300.0) < 60.0]
    r = sigma * rng.standard_normal(t.size) + 0.5 * sigma * np.sin(2 * np.pi * t / period)
    f, p, method = residual_spectrum(t, r)
    assert method == ("Lomb-Scargle" if bursts else "periodogram")
    assert abs(f[np.argmax(p)] - 1.0 / period) < 0.05 / period
    high = f > 0.05  # far from the line: white noise alone, one-sided density 2 sigma^2 / fs
    assert np.median(p[high]) == pytest.approx(2.0 * sigma**2 / fs * np.log(2.0), rel=0.25)


def test_instants_outside_the_record_are_not_drawn(several: Diagnosis) -> None:
    """An instant far outside the record (a power-on at t = 0 on a clock that starts at 1e9 s
    would be one) would squash the time axis: it is skipped, the ones inside are drawn."""
    t0, t1 = float(several.series.t_s[0]), float(several.series.t_s[-1])
    finding = _open_world()[0] | {"where": {"time_s": [t0 - 10.0 * (t1 - t0), 0.5 * (t0 + t1), t1 + 1e9]}}
    fig, ax = plt.subplots()
    assert mark_times(ax, replace(several, effects=[Finding.from_json(finding)]), t0, t1) == 1
    assert float(ax.lines[0].get_xdata()[0]) == pytest.approx(0.5 * (t1 - t0) / 3600.0)
    plt.close(fig)
