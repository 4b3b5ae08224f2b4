"""How calibrate trains its networks: bp by Levenberg-Marquardt when the rows allow it, bp_gd by
the paper's gradient descent, and the record of it a calibration states."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.compensation.calibration import fit, record
from tcbench.compensation.training import bp_algorithm, describe


def test_lm_needs_five_rows_per_weight() -> None:
    assert bp_algorithm("lm", 205, 41) == ("lm", "205 rows >= 5 per weight (41)")
    assert bp_algorithm("lm", 204, 41)[0] == "gd" and "too few for LM" in bp_algorithm("lm", 204, 41)[1]
    assert bp_algorithm("lm", 10**7, 41)[0] == "gd"  # a Jacobian beyond memory
    assert bp_algorithm("gd", 10**4, 41) == ("gd", "the paper's training")
    with pytest.raises(ValueError, match="bp_training must be one of lm, gd"):
        bp_algorithm("adam", 300, 41)


def test_lm_reaches_a_lower_training_error_than_gradient_descent() -> None:
    t = np.arange(0.0, 7200.0)
    temp = 30.0 + 20.0 * np.cos(2.0 * np.pi * t / 3600.0)
    out = 0.02 + 1e-3 * (temp - 20.0) - 2e-5 * (temp - 20.0) ** 2 + np.random.default_rng(0).normal(0.0, 2e-3, t.size)
    rec = record(t, temp, out, np.zeros_like(t))
    lm, gd = fit("bp", [rec], seed=1), fit("bp_gd", [rec], seed=1)
    assert lm.training["algorithm"] == "lm" and lm.training["rows"] == 1440 and lm.training["max_epochs"] == 200
    assert gd.training == {"algorithm": "gd", "max_epochs": 1000, "epochs": 1000, "stopped": "max_epochs",
                           "rows": 1440, "why": "the paper's training"}
    bins = rec.binned(5.0)
    err = {name: np.mean((m.offset(bins) - bins.output) ** 2) for name, m in (("lm", lm), ("gd", gd))}
    assert err["lm"] < err["gd"], err
    short = fit("bp", [record(t[:600], temp[:600], out[:600], np.zeros(600))], seed=1)
    assert short.training["algorithm"] == "gd" and short.training["rows"] == 120  # too few rows for LM
    line = describe("bp", [lm.training, lm.training])
    assert line.startswith("bp: LM (at most 200 iterations; ran ") and "2 restarts; 1440 rows >= 5 per weight" in line
