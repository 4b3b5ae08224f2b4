"""Each gyro pipeline figure writes a valid, non-trivial and small PNG from synthetic inputs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.compensation.gyro import plots
from tcbench.compensation.gyro.pipeline import ModeClasses
from tcbench.signal.allan import allan_deviation

pytestmark = pytest.mark.figures  # rendered: these tests look at the figures (tests/conftest.py)

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
N, K, FS_HZ = 3000, 5, 1.0


def _check_png(path: Path) -> None:
    assert path.exists()
    assert path.read_bytes()[:8] == PNG_SIGNATURE
    assert 5_000 < path.stat().st_size < 300_000, path.stat().st_size


def _modes(n: int, k: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Times (s, 1 Hz) and k modes: a slow drift, sines of rising frequency and white noise."""
    t = np.arange(n) / FS_HZ
    freqs = np.geomspace(1.0 / n, 0.2, k)
    modes = np.sin(2 * np.pi * freqs[:, None] * t) * np.linspace(1.0, 0.2, k)[:, None]
    modes[-1] = 0.3 * rng.standard_normal(n)
    return t, modes


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(0)


def test_modes_figure(tmp_path: Path, rng: np.random.Generator) -> None:
    t, modes = _modes(N, K, rng)
    labels = ("drift", "drift", "mixed", "mixed", "noise")
    freqs = np.geomspace(1.0 / N, 0.2, K)
    out = plots.modes_figure(tmp_path / "fig12.png", t, modes, freqs, labels, "VMD modes")
    assert out == tmp_path / "fig12.png"
    _check_png(out)
    _check_png(plots.modes_figure(tmp_path / "bare.png", t, modes, None, None, "VMD modes"))


def test_modes_figure_long_record(tmp_path: Path, rng: np.random.Generator) -> None:
    """600 000 samples are drawn as a min/max envelope: fast, and the PNG stays small."""
    t, modes = _modes(600_000, 4, rng)
    labels = ("drift", "mixed", "noise", "noise")
    out = plots.modes_figure(tmp_path / "long.png", t, modes, None, labels, "long record")
    _check_png(out)


def test_entropy_classes_figure_with_infinite_entropy(tmp_path: Path) -> None:
    classes = ModeClasses(entropy=np.array([0.01, 0.05, 0.6, 1.3, np.inf]),
                          label=("drift", "drift", "mixed", "noise", "noise"),
                          noise_above=1.0, drift_below=0.1)
    _check_png(plots.entropy_classes_figure(tmp_path / "fig13.png", classes, "sample entropy"))


def test_mixed_tfpf_figure(tmp_path: Path, rng: np.random.Generator) -> None:
    t = np.arange(N) / FS_HZ
    clean = 0.2 * np.sin(2 * np.pi * t / 900.0)
    _check_png(plots.mixed_tfpf_figure(tmp_path / "fig14.png", t, clean + 0.05 * rng.standard_normal(N),
                                       clean + 0.01 * rng.standard_normal(N), "mixed part"))


def test_drift_prediction_figure(tmp_path: Path, rng: np.random.Generator) -> None:
    t = np.arange(N) / FS_HZ
    temp = 25.0 + 20.0 * np.tanh((t - 1500.0) / 400.0)
    drift = 1e-4 * (temp - 25.0) ** 2
    predicted = 0.9 * drift + 2e-3 + 5e-4 * rng.standard_normal(N)
    _check_png(plots.drift_prediction_figure(tmp_path / "fig17.png", t, temp, drift, predicted, "drift"))


def test_final_output_figure(tmp_path: Path, rng: np.random.Generator) -> None:
    t = np.arange(N) / FS_HZ
    truth = np.zeros(N)
    raw = 0.05 * t / t[-1] + 0.02 * rng.standard_normal(N)
    final = 0.005 * rng.standard_normal(N)
    _check_png(plots.final_output_figure(tmp_path / "fig18.png", t, raw, final, "final output"))
    _check_png(plots.final_output_figure(tmp_path / "truth.png", t, raw, final, "final output",
                                         true_rate=truth))


def test_allan_methods_figure(tmp_path: Path, rng: np.random.Generator) -> None:
    names = ("raw", "oracle", "WTD", "BP", "EMD+WTD+SA-BP", "MOVMD-TFPF+BAS-Elman")
    curves = {name: allan_deviation(s * rng.standard_normal(N) + np.cumsum(rng.standard_normal(N)) * 1e-5,
                                    FS_HZ, "octave")
              for name, s in zip(names, np.geomspace(1e-2, 1e-3, len(names)), strict=True)}
    out = plots.allan_methods_figure(tmp_path / "fig19.png", curves, "Allan deviation",
                                     annotations={"WTD": "bandwidth 0.03 Hz"})
    _check_png(out)
    _check_png(plots.allan_methods_figure(tmp_path / "dps.png", curves, "Allan deviation", units="deg/s"))
    with pytest.raises(ValueError, match="units"):
        plots.allan_methods_figure(tmp_path / "bad.png", curves, "Allan deviation", units="rad/s")


def test_pareto_figure(tmp_path: Path, rng: np.random.Generator) -> None:
    all_f = rng.uniform(0.0, 1.0, (300, 2)) + 0.3
    f1 = np.linspace(0.3, 1.0, 12)
    front_f = np.column_stack((f1, 0.3 / f1))
    front_x = np.column_stack((rng.integers(3, 12, 12), rng.uniform(500.0, 10_000.0, 12)))
    out = plots.pareto_figure(tmp_path / "fig11.png", front_f, all_f, front_f[5], title="MOPSO Pareto front",
                              front_x=front_x)
    _check_png(out)
    _check_png(plots.pareto_figure(tmp_path / "bare.png", front_f, None, None, title="front only"))
