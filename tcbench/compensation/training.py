"""How ``tcbench calibrate`` trains its networks (``bp``, ``elman``), and the record of it that
the calibration states.

``bp`` is trained by Levenberg-Marquardt (:class:`~tcbench.learners.bp.BPNetwork`'s ``lm``
training: MINPACK-style damping, at most 200 iterations) when the rows allow it, else by gradient
descent with momentum (``gd``, 1000 epochs, the paper's training): LM needs at least
:data:`LM_ROWS_PER_PARAM` rows per weight (a 2-10-1 network has 41, so 205 rows: with fewer it
can thread every bin and its output between them is arbitrary; gradient descent's early stop is
then the gentler fit) and a Jacobian of at most :data:`LM_MAX_FLOATS` floats. The calibration
shows both: ``bp`` (LM when allowed) and ``bp_gd`` (gradient descent, 1000 epochs) — which one
generalises better is a property of the record (LM reaches a lower training error and, on
~300-600 bins of a chamber cycle, can thread the noise of the bins with its 41 weights; its seeds
then spread widely). ``elman`` keeps its own training (Adam, 500 epochs, BPTT
windows of 32 steps).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from tcbench.compensation.record import Record

BP_TRAININGS = ("lm", "gd")
LM_ROWS_PER_PARAM = 5
LM_MAX_FLOATS = 5e7


def bp_algorithm(requested: str, rows: int, n_params: int) -> tuple[str, str]:
    """The training ``bp`` gets on ``rows`` rows (``requested``: ``lm`` when allowed, or ``gd``)
    and why."""
    if requested not in BP_TRAININGS:
        raise ValueError(f"bp_training must be one of {', '.join(BP_TRAININGS)}, got {requested!r}")
    if requested == "gd":
        return "gd", "the paper's training"
    if rows < LM_ROWS_PER_PARAM * n_params:
        return "gd", f"{rows} rows < {LM_ROWS_PER_PARAM} per weight ({n_params}): too few for LM"
    if rows * n_params > LM_MAX_FLOATS:
        return "gd", f"{rows} rows x {n_params} weights: the LM Jacobian would exceed {LM_MAX_FLOATS:.0e} floats"
    return "lm", f"{rows} rows >= {LM_ROWS_PER_PARAM} per weight ({n_params})"


def _bp_params(requested: str, rows: int, seed: int) -> tuple[dict[str, Any], str]:
    """``bp``'s parameters on ``rows`` rows: the training :func:`bp_algorithm` picks, and why."""
    from tcbench.learners import registry

    probe = registry.create("bp", 2, None, np.random.default_rng(seed))
    algorithm, why = bp_algorithm(requested, rows, probe.n_params)
    return {"training": algorithm}, why


# The learners whose parameters the rows decide: ``(bp_training, rows, seed) -> (params, why)``;
# any other learner is trained with its default parameters.
TRAINING_CHOICES: dict[str, Callable[[str, int, int], tuple[dict[str, Any], str]]] = {"bp": _bp_params}


def fit_network(method: str, train: Sequence[Record], seed: int, bin_s: float | None,
                bp_training: str = "lm") -> tuple[Any, dict[str, Any]]:
    """A network ``method`` fitted on ``train`` (its normalisation on the samples, its training on
    the ``bin_s`` bins, see :func:`tcbench.compensation.calibration.fit`) and its training record:
    algorithm, epoch or iteration limit, iterations run, why it stopped, rows, why that algorithm."""
    from tcbench.learners import registry

    rows = [r.binned(bin_s) for r in train] if bin_s else list(train)
    x = np.column_stack([np.concatenate([r.temp_c for r in rows]), np.concatenate([r.rate_c_per_s for r in rows])])
    y = np.concatenate([r.output - r.truth for r in rows])
    choose = TRAINING_CHOICES.get(method)
    params, why = choose(bp_training, y.size, seed) if choose is not None else (None, "its default")
    learner = registry.create(method, 2, params, np.random.default_rng(seed))
    learner.scale_to(np.column_stack([np.concatenate([r.temp_c for r in train]),
                                      np.concatenate([r.rate_c_per_s for r in train])]),
                     np.concatenate([r.output - r.truth for r in train]))
    history = learner.fit(x, y)
    p = learner.params
    limit = p.max_epochs if hasattr(p, "max_epochs") else p.epochs
    return learner, {"algorithm": p.training, "max_epochs": int(limit), "epochs": int(history.iterations),
                     "stopped": history.stopped, "rows": int(y.size), "why": why}


def describe(method: str, runs: Sequence[dict[str, Any]]) -> str:
    """``bp: LM (at most 200 iterations; ran 37-200, 5 restarts; 270 rows >= 5 per weight (41))``."""
    algs = sorted({r["algorithm"] for r in runs})
    ran = [r["epochs"] for r in runs]
    span = f"{min(ran)}" if min(ran) == max(ran) else f"{min(ran)}-{max(ran)}"
    unit = "iterations" if algs == ["lm"] else "epochs"
    return (f"{method}: {'/'.join(a.upper() for a in algs)} (at most {runs[0]['max_epochs']} {unit}; ran {span}, "
            f"{len(runs)} restart{'s' * (len(runs) != 1)}; {runs[0]['why']})")
