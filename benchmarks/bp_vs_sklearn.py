"""Benchmark tcbench's BP network (Levenberg-Marquardt) against scikit-learn's MLPRegressor.

Task: the seed 000 MSRA compensation model (§2.1, a 2-10-1 network with tanh hidden neurons and
a linear output). Data come from tcbench's simulator, one device (``device_seed=0``) through the
full-temperature protocol (-40..60 degC) five times: runs 0-2 train, runs 3-4 test. Only the
labelled four-position rows (``position`` non-empty) are used; inputs are [output (Hz),
temperature (degC)], the target is the applied acceleration (g).

Both sides see the same min-max scaling to [-1, 1] of inputs and target (tcbench's built-in
:class:`~tcbench.learners.base.Scaler`; for scikit-learn a ``Pipeline`` with
``MinMaxScaler((-1, 1))`` inside a ``TransformedTargetRegressor`` with the same scaler), and the
wall time covers scaling + training. scikit-learn runs with its defaults (and once more with lbfgs
unleashed: ``tol=0, max_iter=1000``) apart from the network
shape (``hidden_layer_sizes=(10,), activation="tanh"``) and ``solver`` (``lbfgs``; ``adam`` as a
second row); its ``random_state`` and tcbench's ``rng`` take the repeat index. tcbench runs
``training="lm"`` (Levenberg-Marquardt on the normal equations with an analytic Jacobian and
``trainlm``'s damping schedule) once per LM budget of ``--lm-epochs`` (iterations), one row each
(200 is tcbench's default), and every
tcbench row is checked against every scikit-learn row. The repeats of all methods are
interleaved, after one untimed warm-up fit each, so background load affects them alike. RMSEs
are in micro-g (ug) on the training and test rows.

Usage::

    python benchmarks/bp_vs_sklearn.py --repeats 5
"""

from __future__ import annotations

import statistics
import time
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from common import (
    add_json,
    command_line,
    environment,
    environment_line,
    parser_for,
    progress,
    table_head,
    table_row,
    write_json,
)
from sklearn.compose import TransformedTargetRegressor
from sklearn.exceptions import ConvergenceWarning
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import MinMaxScaler
from threadpoolctl import threadpool_info, threadpool_limits

from tcbench.learners.bp import BPNetwork
from tcbench.sensors.simulate import simulate_recording

DEFAULT_JSON = Path(__file__).with_name("bp_vs_sklearn.json")
TRAIN_SEEDS, TEST_SEEDS = (0, 1, 2), (3, 4)
UG_PER_G = 1e6

Data = tuple[np.ndarray, np.ndarray]
Fit = Callable[[np.ndarray, np.ndarray, int], tuple[Callable[[np.ndarray], np.ndarray], int]]


@dataclass(frozen=True)
class Run:
    method: str
    repeat: int
    seconds: float
    iterations: int
    train_rmse_ug: float
    test_rmse_ug: float


def labelled_rows(seeds: tuple[int, ...]) -> Data:
    """[output (Hz), temperature (degC)] and the applied acceleration (g) of the labelled rows."""
    xs, ys = [], []
    for seed in seeds:
        rec = simulate_recording("msra", "fulltemp", device_seed=0, seed=seed)
        pos = rec.position
        assert pos is not None
        keep = np.array([p is not None and p != "" for p in pos])
        xs.append(np.column_stack([rec.output[keep], rec.temperature_c[keep]]))
        ys.append(rec.input[keep])
    return np.vstack(xs), np.concatenate(ys)


def tcbench_lm(epochs: int) -> Fit:
    def fit(x: np.ndarray, y: np.ndarray, repeat: int) -> tuple[Callable[[np.ndarray], np.ndarray], int]:
        net = BPNetwork(2, {"training": "lm", "epochs": epochs}, rng=np.random.default_rng(repeat))
        history = net.fit(x, y)
        return net.predict, history.iterations

    return fit


def sklearn_mlp(solver: str, **options: float) -> Fit:
    def fit(x: np.ndarray, y: np.ndarray, repeat: int) -> tuple[Callable[[np.ndarray], np.ndarray], int]:
        mlp = MLPRegressor(hidden_layer_sizes=(10,), activation="tanh", solver=solver, random_state=repeat,
                           **options)
        model = TransformedTargetRegressor(
            regressor=Pipeline([("scale", MinMaxScaler(feature_range=(-1, 1))), ("mlp", mlp)]),
            transformer=MinMaxScaler(feature_range=(-1, 1)),
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            model.fit(x, y)
        return model.predict, int(model.regressor_.named_steps["mlp"].n_iter_)

    return fit


def rmse_ug(predicted: np.ndarray, target: np.ndarray) -> float:
    return UG_PER_G * float(np.sqrt(np.mean((predicted - target) ** 2)))


def run_once(name: str, fit: Fit, train: Data, test: Data, repeat: int) -> Run:
    start = time.perf_counter()
    predict, iterations = fit(*train, repeat)
    seconds = time.perf_counter() - start
    return Run(name, repeat, seconds, iterations, rmse_ug(predict(train[0]), train[1]),
               rmse_ug(predict(test[0]), test[1]))


def summary(runs: list[Run], methods: list[str]) -> list[dict[str, float | str]]:
    rows: list[dict[str, float | str]] = []
    for method in methods:
        mine = [r for r in runs if r.method == method]
        rows.append({
            "method": method,
            "median_seconds": statistics.median(r.seconds for r in mine),
            "median_iterations": statistics.median(r.iterations for r in mine),
            "median_train_rmse_ug": statistics.median(r.train_rmse_ug for r in mine),
            "median_test_rmse_ug": statistics.median(r.test_rmse_ug for r in mine),
            "min_test_rmse_ug": min(r.test_rmse_ug for r in mine),
            "max_test_rmse_ug": max(r.test_rmse_ug for r in mine),
        })
    return rows


def ratios(rows: list[dict[str, float | str]]) -> list[dict[str, float | str | bool]]:
    """For each tcbench row against each scikit-learn row: time ratio sklearn / tcbench, test
    RMSE ratio sklearn / tcbench, and whether the target (>= 3x faster, equal or better test
    RMSE) is met."""
    out: list[dict[str, float | str | bool]] = []
    for ours in (r for r in rows if str(r["method"]).startswith("tcbench")):
        for peer in (r for r in rows if str(r["method"]).startswith("sklearn")):
            time_ratio = float(peer["median_seconds"]) / float(ours["median_seconds"])
            rmse_ratio = float(peer["median_test_rmse_ug"]) / float(ours["median_test_rmse_ug"])
            out.append({"tcbench": ours["method"], "sklearn": peer["method"],
                        "time_ratio": time_ratio, "test_rmse_ratio": rmse_ratio,
                        "target_met": time_ratio >= 3 and rmse_ratio >= 1})
    return out


def blas_threads() -> str:
    """BLAS libraries and their thread counts, e.g. ``openblas 0.3.31 (2 threads)``."""
    info = [i for i in threadpool_info() if i.get("user_api") == "blas"]
    return ", ".join(f"{i['internal_api']} {i.get('version')} ({i['num_threads']} threads)" for i in info) or "none"


def main(argv: list[str] | None = None) -> None:
    parser = parser_for(__doc__ or "")
    parser.add_argument("--repeats", type=int, default=5, help="fits per method (median reported)")
    parser.add_argument("--lm-epochs", type=int, nargs="+", default=[3, 5, 10, 20, 50, 200],
                        help="tcbench LM budgets (limit on residual evaluations), one row each")
    parser.add_argument("--blas-threads", type=int, default=None,
                        help="limit BLAS threads of every method (default: leave as found)")
    add_json(parser, DEFAULT_JSON)
    args = parser.parse_args(argv)
    if args.repeats < 1 or min(args.lm_epochs) < 1:
        parser.error("--repeats and --lm-epochs must be >= 1")

    train, test = labelled_rows(TRAIN_SEEDS), labelled_rows(TEST_SEEDS)
    fits: dict[str, Fit] = {f"tcbench bp lm (epochs={e})": tcbench_lm(e) for e in args.lm_epochs}
    fits |= {f"sklearn MLPRegressor {s}": sklearn_mlp(s) for s in ("lbfgs", "adam")}
    # a stronger peer than the defaults: lbfgs without its early stop, up to 1000 iterations
    fits["sklearn MLPRegressor lbfgs (tol=0, max_iter=1000)"] = sklearn_mlp("lbfgs", tol=0.0, max_iter=1000)
    runs = []
    with threadpool_limits(limits=args.blas_threads, user_api="blas"):
        blas = blas_threads()
        for fit in fits.values():
            fit(*train, 0)  # warm-up
        for repeat in range(args.repeats):
            for name, fit in fits.items():
                run = run_once(name, fit, train, test, repeat)
                runs.append(run)
                progress(f"repeat {repeat} {name}: {run.seconds:.3f} s, {run.iterations} it, "
                         f"test {run.test_rmse_ug:.1f} ug")
    rows = summary(runs, list(fits))
    checks = ratios(rows)

    env = environment("scipy", "scikit-learn", "threadpoolctl", blas=blas)
    command = command_line(argv)
    print("## BP (Levenberg–Marquardt) vs scikit-learn MLPRegressor\n")
    print(f"Command: `{command}`\n")
    print(environment_line(env, f"scipy {env['scipy']}, scikit-learn {env['scikit-learn']}")
          + f" BLAS: {env['blas']}.\n")
    print(f"Data: {len(train[1])} training rows (runs 0-2), {len(test[1])} test rows (runs 3-4); "
          f"{args.repeats} repeats.\n")
    columns = ["method", "median wall time (s)", "iterations (median)", "train RMSE (µg)",
               "test RMSE (µg)", "test RMSE min .. max (µg)"]
    print("\n".join(table_head(columns, "lrrrrr")))
    for row in rows:
        print(table_row([
            row["method"], f"{row['median_seconds']:.3f}", f"{row['median_iterations']:.0f}",
            f"{row['median_train_rmse_ug']:.3g}", f"{row['median_test_rmse_ug']:.3g}",
            f"{row['min_test_rmse_ug']:.3g} .. {row['max_test_rmse_ug']:.3g}",
        ]))
    print("\nTarget: >= 3x faster than scikit-learn with equal or better median test RMSE.\n")
    print("\n".join(table_head(["tcbench", "scikit-learn", "time sklearn / tcbench",
                                 "test RMSE sklearn / tcbench", "target"], "llrrl")))
    for c in checks:
        print(table_row([c["tcbench"], c["sklearn"], f"{c['time_ratio']:.3g}x",
                         f"{c['test_rmse_ratio']:.3g}", "met" if c["target_met"] else "not met"]))
    write_json(args.json, {
        "benchmark": "bp_vs_sklearn",
        "train_seeds": list(TRAIN_SEEDS), "test_seeds": list(TEST_SEEDS),
        "train_rows": len(train[1]), "test_rows": len(test[1]),
        "repeats": args.repeats, "lm_epochs": args.lm_epochs, "blas_threads": args.blas_threads,
        "command": command, "environment": env, "results": rows, "ratios": checks,
        "runs": [asdict(r) for r in runs],
    })


if __name__ == "__main__":
    main()
