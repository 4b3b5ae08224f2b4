"""Plots and markdown report of a diagnosis (tcbench.diagnose.report.plots, tcbench.diagnose.report.markdown)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import Diagnosis, diagnose
from tcbench.diagnose.report.markdown import render_markdown
from tcbench.diagnose.report.plots import plot_allan, plot_evidence, write_plots
from tcbench.diagnose.result import Confusion
from tcbench.sensors.recording import make_recording

pytestmark = pytest.mark.figures  # rendered: these tests look at the figures (tests/conftest.py)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def found() -> Diagnosis:
    """A diagnosis that finds an effect (hysteresis hidden in a gyro recording)."""
    rec, _ = concealed_recording("gyro", "hysteresis", 4)
    return diagnose(rec, name="gyro-hysteresis")


@pytest.fixture(scope="module")
def control() -> Diagnosis:
    """A diagnosis of a recording with nothing missing: 2 h at 1 Hz through one temperature cycle,
    the output a line in temperature plus white noise (the minimal model), read by a thermometer
    with 0.01 degC of white noise (so the default smoothing window: one diagnosis, not two)."""
    rng = np.random.default_rng(0)
    t_s = np.arange(7200.0)
    temp_c = 20.0 + 10.0 * np.sin(2.0 * np.pi * t_s / t_s[-1])
    output = 0.01 * temp_c + rng.normal(0.0, 0.01, t_s.size)
    rec = make_recording(t_s, temp_c + rng.normal(0.0, 0.01, t_s.size), np.zeros(t_s.size), output, sensor="gyro",
                         sample_rate_hz=1.0, device_id="control")
    return diagnose(rec, name="gyro-control")


def _assert_pngs(out: Path, plots: dict[str, str]) -> None:
    assert set(plots) == {"residuals", "allan", "evidence", "spectrum"}
    assert sorted(plots.values()) == ["allan.png", "evidence.png", "residuals.png", "spectrum.png"]
    for filename in plots.values():
        data = (out / filename).read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 10_000


@pytest.mark.parametrize("which", ["found", "control"])
def test_plots_written(which: str, request: pytest.FixtureRequest, tmp_path: Path) -> None:
    d = request.getfixturevalue(which)
    out = tmp_path / "plots"
    _assert_pngs(out, write_plots(d, out))


def test_markdown_with_effect(found: Diagnosis) -> None:
    assert found.effects, "the fixture should find the hidden effect"
    plots = {"residuals": "residuals.png", "allan": "allan.png", "evidence": "evidence.png"}
    md = render_markdown(found, plots)
    assert md.startswith("# Diagnosis of gyro-hysteresis (gyro)")
    assert found.verdict in md
    for effect in found.effect_ids:
        assert f"### {effect}" in md
    for name, filename in plots.items():
        assert f"![{name}]({filename})" in md
    for e in found.candidates:
        assert f"| {e.effect} | {e.status} |" in md
    assert "nothing missing" not in md.lower()
    assert "degC" in md and found.unit in md


def test_markdown_control_says_nothing_missing(control: Diagnosis) -> None:
    assert not control.effects
    md = render_markdown(control, {"residuals": "residuals.png"})
    assert "nothing missing" in md.lower()
    assert control.verdict in md and "![residuals](residuals.png)" in md


def test_missing_allan_and_confusable_pair(found: Diagnosis, tmp_path: Path) -> None:
    """No Allan deviation (bursts) and a confusable pair: both plots still written, the pair and
    the test that separates it in the markdown."""
    test = "soaks approached from above and from below"
    d = replace(found, series=replace(found.series, allan_before=None, allan_after=None),
                confusable=[Confusion(("hysteresis", "thermal_lag"), test)])
    for plot, name in ((plot_allan, "allan.png"), (plot_evidence, "evidence.png")):
        path = plot(d, tmp_path / name)
        assert path.read_bytes()[:8] == PNG_MAGIC
    md = render_markdown(d, {})
    assert "hysteresis** cannot be told from **thermal_lag" in md and test in md
