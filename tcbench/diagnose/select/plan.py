"""The statistics of a diagnosis, sized to the recording (docs/concepts/diagnosis-report.md).

A diagnosis scores effects by blocked cross-validation and tests them against the residual's
slow noise. Both need time spans that fit the recording:

- **CV blocks** of ``block_s``: a 24th of the recording (at least four blocks per fold), at
  least two smoothing windows (so a held-out block is not predicted by the smoothed thermometer
  of its neighbours) and at most 15 min (the length the library proof was calibrated with on
  8-12 h records, which keep it). A 70-min chamber cycle gets 18 blocks of 4 min instead of
  five of 15 min, so leaving one fold out never removes a whole branch of the temperature cycle.
- **Clusters** of the robust Wald test: ``cluster_s`` a 32nd of the recording, within
  2.5 smoothing windows and 15 min.
- **The significance test** (an object of :mod:`tcbench.diagnose.select.significance`): the
  cluster-robust Wald statistic needs many clusters to estimate the variance of slow noise; with
  fewer than ``min_clusters`` the recording cannot support it and the diagnosis uses a
  surrogate test instead (:func:`tcbench.diagnose.select.surrogate.surrogate_test`): a parametric
  bootstrap under a noise model with the spectrum of the candidate model's own residual.
- **The shortest record** (:func:`min_full_duration_s`): five folds of one block each, a block
  two smoothing windows long: 20 min at the default 120 s window.

The numbers (folds, blocks and clusters per record, windows per block and cluster, the longest
block, the fewest clusters) are :class:`~tcbench.diagnose.settings.PlanSettings`. Shorter, a fold holds less
  than one whole block, or none, and its held-out samples are predicted by the smoothed
  thermometer of their own neighbours. A shorter record gets the tests its length allows
  (:mod:`tcbench.diagnose.short.short_record`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.diagnose.select.significance import ROBUST_WALD, SURROGATE, SignificanceTest, significance_tests
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings
from tcbench.diagnose.signals import DiagnosisData

__all__ = ["ROBUST_WALD", "SURROGATE", "StatsPlan", "min_full_duration_s", "plan_for"]


@dataclass(frozen=True)
class StatsPlan:
    """Block length (s) and fold count of the cross-validation, cluster length (s) and count of
    the robust test, and the significance test the recording supports (the robust Wald test or
    the surrogate test, :mod:`tcbench.diagnose.select.significance`)."""

    block_s: float
    k: int
    cluster_s: float
    n_clusters: int
    test: SignificanceTest

    def to_json(self) -> dict[str, float | int | str]:
        return {"cv_block_s": self.block_s, "folds": self.k, "cluster_s": self.cluster_s,
                "clusters": self.n_clusters, "significance_test": self.test.name}


def plan_for(data: DiagnosisData, settings: DiagnoseSettings = DEFAULTS) -> StatsPlan:
    """The statistics for ``data`` (see module doc), sized by ``settings.plan``; the tests at
    ``settings``' Wald threshold and surrogate level."""
    plan = settings.plan
    span = float(data.t_s[-1] - data.t_s[0])
    block_s = float(np.clip(span / plan.blocks_per_record, min(plan.block_windows * data.smooth_s, plan.max_block_s),
                            plan.max_block_s))
    cluster_s = float(np.clip(span / plan.clusters_per_record,
                              min(plan.cluster_windows * data.smooth_s, plan.max_block_s), plan.max_block_s))
    n_clusters = int(np.floor(span / cluster_s)) + 1
    robust, surrogate = significance_tests(settings)
    test = robust if n_clusters >= plan.min_clusters else surrogate
    return StatsPlan(block_s, plan.folds, cluster_s, n_clusters, test)


def min_full_duration_s(settings: DiagnoseSettings = DEFAULTS, smooth_s: float | None = None) -> float:
    """The shortest record (s) a full diagnosis takes: ``settings.plan.folds`` cross-validation
    folds of one block each, a block ``settings.plan.block_windows`` thermometer-smoothing windows
    of ``smooth_s`` (default ``settings.smoothing.default_window_s``) long (1200 s by default)."""
    window_s = settings.smoothing.default_window_s if smooth_s is None else smooth_s
    return settings.plan.folds * settings.plan.block_windows * window_s
