"""The plugin's own tests: tcbench's contract checker and a convergence check."""

import numpy as np

from tcbench import check_optimizer
from tcbench_de.de import DifferentialEvolution, distinct_donors


def test_contract() -> None:
    assert check_optimizer(DifferentialEvolution) > 0


def test_donors_distinct() -> None:
    d = distinct_donors(6, np.random.default_rng(0))
    assert all(len({i, *row}) == 4 for i, row in enumerate(d))


def test_converges_on_sphere() -> None:
    opt = DifferentialEvolution(np.full(3, -5.0), np.full(3, 5.0), 3000, np.random.default_rng(1))
    while not opt.done:
        x = opt.ask()
        opt.tell(x, np.sum(x * x, axis=1))
    assert opt.best.f < 1e-6
