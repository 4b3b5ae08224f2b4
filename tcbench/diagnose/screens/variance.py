"""Variance: noise whose level changes with temperature or with time.

The quality factor and damping of a resonator, the converter's reference and an amplifier's
noise all change with temperature; a part can also get noisier as it ages or after an event.
The model's white noise is one sigma for the whole record, so such a record leaves no mean
structure, only a level of scatter that follows temperature or time.

Test (:func:`find_variance`), on the final model's in-sample residual ``r``:

1. **Pairs**: ``d = r[i+1] - r[i]`` for non-overlapping pairs of consecutive samples in the same
   run of constant input, no farther apart than 1.5 sample intervals. Differencing removes the
   slow structure (a missed temperature term, flicker) that would otherwise look like scatter;
   non-overlapping pairs are independent under white noise, each ``d ~ N(0, 2 sigma^2)``.
   ``|d|`` is clipped at ``clip_sigma`` robust sigmas, so a residual glitch cannot make a block noisy.
2. **Blocks**: consecutive pairs in ``B`` blocks of ``m`` or ``m + 1 >=`` ``min_pairs`` pairs (at most
   ``max_blocks`` blocks); ``v_b = log(mean d^2)`` per block, ``x_b`` its mean temperature
   (or time).
3. **F test**: regress ``v_b`` on ``[1, z, z^2]`` (``z`` the standardised temperature, or time)
   against a constant: ``F = ((RSS0 - RSS1) / 2) / (RSS1 / (B - 3))``, which follows ``F(2, B - 3)``
   under constant variance whatever the shape of the noise (its scatter is estimated from the
   blocks themselves). Temperature and time each at ``alpha`` / 2 (Bonferroni: 1 %
   family-wise); when both pass, the one with the larger F names the finding. A record with
   fewer than ``min_blocks`` blocks is not tested and says so.
   **Size**: a significant change is reported only when the noisiest bin's sigma (step 4) is at
   least ``min_sigma_ratio`` times the quietest's. A long record makes a few per cent
   significant (the concealed gyro with a thermal lag, seed 2: p = 0.004, sigma 0.0022 to 0.0024,
   a chance alarm at the 1 % level); such a change moves the held-out RMSE by well under 1 % and
   is not worth a model term. Under constant noise the bins' ratio scatters by about 5 % (8 bins
   of 50 blocks of 40 pairs).
4. **Where**: the blocks in ``bins`` bins of equal count along temperature (time); the band
   is the run of bins around the noisiest whose log-variance is above the midpoint of the
   noisiest and the quietest bin.
5. **Model**: ``log sigma`` linear in temperature (time), its slope from the blocks' linear
   regression and its level from the pairs; ``model.yaml`` gets ``noise_temperature: {density,
   growth_per_c, ref_c}`` (or ``noise_time: {density, growth_per_h, ref_s}``) in place of
   ``white_noise``, so ``tcbench simulate model=`` draws noise of the same changing level.

The numbers are :class:`~tcbench.diagnose.settings.VarianceSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.stats import f as f_dist

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.settings import DEFAULTS, VarianceSettings
from tcbench.diagnose.signals import MAD_TO_SIGMA

EXPLANATION = {
    "temperature": ("the noise level changes with temperature: the resonator's quality factor and damping, the "
                    "converter's reference or the amplifier's noise vary over temperature"),
    "time": ("the noise level changes with time, not temperature: a part or supply that gets noisier as it runs, "
             "a changed environment (vibration, a fan), or an event part-way through the record"),
}
CONFIRM_WITH = {
    "temperature": "Allan deviation per temperature band from soaks at several temperatures, heating and cooling",
    "time": "a second record at constant temperature of the same length, and the environment's log (vibration, supply)",
}


@dataclass(frozen=True)
class Test:
    """One F test: the regressor (``temperature`` or ``time``), F, its p-value, the blocks'
    linear slope of log sigma per unit of the regressor, and the band of the noisiest bins."""

    against: str
    f: float
    p_value: float
    slope: float
    band: tuple[float, float]
    sigma_band: tuple[float, float]  # per-sample sigma of the quietest and the noisiest bin
    profile: tuple[tuple[float, ...], tuple[float, ...]] = ((), ())  # bins' mean regressor and per-sample sigma


@dataclass(frozen=True)
class Variance:
    """The variance tests of one record and the finding, if any (``found`` the winning test)."""

    found: Test | None
    tests: list[Test]
    blocks: int
    pairs_per_block: int
    sigma_ref: float  # per-sample sigma at the reference (output unit)
    ref: float  # reference temperature (degC) or time (s) of ``sigma_ref``
    sample_rate_hz: float
    reason: str = ""
    rms_sigma: float = 0.0  # per-sample RMS sigma over the record (output unit): the level sums of squares see
    settings: VarianceSettings = field(default=DEFAULTS.screens.variance, repr=False)

    def model_effect(self) -> tuple[str, dict[str, float]] | None:
        """The effect id and parameters written to ``model.yaml`` in place of ``white_noise``."""
        if self.found is None:
            return None
        density = self.sigma_ref / np.sqrt(self.sample_rate_hz)
        if self.found.against == "temperature":
            return "noise_temperature", {"density": float(density), "growth_per_c": self.found.slope, "ref_c": self.ref}
        return "noise_time", {"density": float(density), "growth_per_h": 3600.0 * self.found.slope, "ref_s": self.ref}

    def finding(self, unit: str) -> Finding:
        """The report.json ``effects`` entry (shape ``variance``)."""
        test = self.found
        assert test is not None
        effect, params = self.model_effect()  # type: ignore[misc]
        key = "temperature_c" if test.against == "temperature" else "time_s"
        band = [round(test.band[0], 3), round(test.band[1], 3)]
        where: dict[str, Any] = {key: band}
        span = "degC" if test.against == "temperature" else "s"
        return Finding(
            id=effect, shape="variance", library=False,
            params={**params, "sigma_quiet": test.sigma_band[0], "sigma_noisy": test.sigma_band[1]},
            where=where,
            evidence={"test": "F test of the blocks' log variance of paired differences on a quadratic in "
                              f"{test.against} against a constant",
                      "f": round(test.f, 3), "p_value": float(test.p_value), "level": self.settings.alpha / 2,
                      "blocks": self.blocks, "pairs_per_block": self.pairs_per_block,
                      "other": [{"against": t.against, "f": round(t.f, 3), "p_value": float(t.p_value)}
                                for t in self.tests if t is not test]},
            explanation=(f"the white-noise sigma goes from {test.sigma_band[0]:.4g} to {test.sigma_band[1]:.4g} {unit} "
                         f"and is highest between {band[0]:.6g} and {band[1]:.6g} {span}: "
                         + EXPLANATION[test.against]),
            confirm_with=CONFIRM_WITH[test.against],
        )

    def relative_sigma(self, temp_c: np.ndarray, t_s: np.ndarray) -> np.ndarray:
        """Per-sample noise level relative to the record's RMS (1 where nothing was found): the
        found test's bins interpolated at each sample's temperature (degC) or time (s)."""
        if self.found is None:
            return np.ones(np.shape(t_s))
        centre, sigma = (np.asarray(a) for a in self.found.profile)
        x = temp_c if self.found.against == "temperature" else t_s
        out = np.interp(x, centre, sigma)
        return out / np.sqrt(np.mean(out**2))

    def statistics(self) -> dict[str, Any]:
        """A line for report.json ``statistics``: how the test ran, or why it did not."""
        if self.reason:
            return {"not_tested": self.reason}
        return {"blocks": self.blocks, "pairs_per_block": self.pairs_per_block,
                "min_sigma_ratio": self.settings.min_sigma_ratio,
                "tests": {t.against: {"f": round(t.f, 3), "p_value": float(t.p_value),
                                      "sigma_ratio": round(t.sigma_band[1] / t.sigma_band[0], 4)} for t in self.tests}}


def paired_differences(t_s: np.ndarray, residual: np.ndarray, run_id: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index ``i`` of the first sample and ``d = r[i+1] - r[i]`` of non-overlapping pairs of
    consecutive samples in one run, at most 1.5 sample intervals apart."""
    if t_s.size < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    dt = np.diff(t_s)
    ok = (run_id[1:] == run_id[:-1]) & (dt <= 1.5 * float(np.median(dt)))
    start = np.flatnonzero(ok)
    # non-overlapping: keep a start only when the previous kept one is not its predecessor
    keep = np.ones(start.size, dtype=bool)
    chained = np.diff(start) == 1
    if chained.any():  # alternate along each chain of consecutive starts
        chain_id = np.concatenate(([0], np.cumsum(~chained)))
        first = np.flatnonzero(np.concatenate(([True], ~chained)))
        position = np.arange(start.size) - first[chain_id]
        keep = position % 2 == 0
    start = start[keep]
    return start, residual[start + 1] - residual[start]


def _f_test(v: np.ndarray, x: np.ndarray) -> tuple[float, float, float]:
    """F and p of ``v`` on ``[1, z, z^2]`` against a constant, and the linear slope of ``v`` on ``x``."""
    z = (x - x.mean()) / (x.std() or 1.0)
    design = np.column_stack([np.ones_like(z), z, z * z])
    beta, *_ = np.linalg.lstsq(design, v, rcond=None)
    rss1 = float(np.sum((v - design @ beta) ** 2))
    rss0 = float(np.sum((v - v.mean()) ** 2))
    dof = v.size - 3
    f = ((rss0 - rss1) / 2.0) / max(rss1 / dof, 1e-300)
    slope = float(np.polyfit(x, v, 1)[0]) if np.ptp(x) > 0 else 0.0
    return float(f), float(f_dist.sf(f, 2, dof)), slope


def _band(v: np.ndarray, x: np.ndarray, n_bins: int) -> tuple[tuple[float, float], np.ndarray, np.ndarray]:
    """The noisiest band of ``x``, and the mean ``x`` and mean ``v`` of each of ``n_bins`` bins."""
    order = np.argsort(x, kind="stable")
    bins = np.array_split(order, n_bins)
    level = np.array([v[b].mean() for b in bins])
    centre = np.array([x[b].mean() for b in bins])
    lo_x = np.array([x[b].min() for b in bins])
    hi_x = np.array([x[b].max() for b in bins])
    top = int(np.argmax(level))
    above = level >= 0.5 * (level.max() + level.min())
    breaks = np.flatnonzero(~above)
    left = int(breaks[breaks < top].max() + 1) if (breaks < top).any() else 0
    right = int(breaks[breaks > top].min() - 1) if (breaks > top).any() else n_bins - 1
    return (float(lo_x[left]), float(hi_x[right])), centre, level


def find_variance(t_s: np.ndarray, temp_c: np.ndarray, residual: np.ndarray, run_id: np.ndarray,
                  sample_rate_hz: float, *, settings: VarianceSettings = DEFAULTS.screens.variance) -> Variance:
    """The variance tests of ``residual`` (output unit) against temperature ``temp_c`` (degC)
    and time ``t_s`` (s); see the module doc."""
    start, d = paired_differences(t_s, np.asarray(residual, dtype=float), run_id)
    blocks = min(settings.max_blocks, d.size // settings.min_pairs)
    scale = float(MAD_TO_SIGMA * np.median(np.abs(d))) if d.size else 0.0
    sigma = scale / np.sqrt(2.0)
    if blocks < settings.min_blocks or not scale > 0:
        why = (f"too few pairs of consecutive samples ({d.size}) for {settings.min_blocks} blocks of "
               f"{settings.min_pairs}" if blocks < settings.min_blocks else "the residual has no sample-to-sample scatter")
        return Variance(None, [], blocks, 0, sigma, 0.0, sample_rate_hz, reason=why, settings=settings)
    m = d.size // blocks
    edges = (np.arange(blocks) * d.size) // blocks  # blocks of m or m + 1 pairs, every pair used
    sizes = np.diff(np.append(edges, d.size))
    d2 = np.minimum(np.abs(d), settings.clip_sigma * scale) ** 2
    v = np.log(np.add.reduceat(d2, edges) / sizes)
    mid = 0.5 * (t_s[start] + t_s[start + 1])
    temps = 0.5 * (temp_c[start] + temp_c[start + 1])
    tests = []
    for against, x_pairs in (("temperature", temps), ("time", mid)):
        x = np.add.reduceat(x_pairs, edges) / sizes
        f, p, slope = _f_test(v, x)
        band, centre, level = _band(v, x, settings.bins)
        sigma_bins = np.sqrt(np.exp(level) / 2.0)  # log mean d^2 = log(2 sigma^2) (+ a bias common to all blocks)
        tests.append(Test(against, f, p, 0.5 * slope, band, (float(sigma_bins.min()), float(sigma_bins.max())),
                          (tuple(centre.tolist()), tuple(sigma_bins.tolist()))))
    passed = [t for t in tests if t.p_value < 0.5 * settings.alpha
              and t.sigma_band[1] >= settings.min_sigma_ratio * t.sigma_band[0]]
    found = max(passed, key=lambda t: t.f) if passed else None
    ref, sigma_ref = 0.0, sigma
    if found is not None:
        x_pairs = temps if found.against == "temperature" else mid
        ref = float(np.round(np.median(x_pairs), 3))
        sigma_ref = float(np.sqrt(np.mean(d2 * np.exp(-2.0 * found.slope * (x_pairs - ref))) / 2.0))
    rms = float(np.sqrt(np.mean(d2) / 2.0))
    return Variance(found, tests, blocks, m, sigma_ref, ref, sample_rate_hz, rms_sigma=rms, settings=settings)
