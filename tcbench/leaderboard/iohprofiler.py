"""Runs in IOHprofiler's format, as ``ioh.logger.Analyzer`` writes them, for IOHanalyzer.

One run of a single-objective task is written into its own folder (parallel jobs never share a
file): ``IOHprofiler_f<id>_<name>.json`` (meta data: suite, function, algorithm, attributes
and, per dimension, the runs with instance, evaluations used and best point) and
``data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat``: per run a header line ``evaluations raw_y``
and one line per improvement, as ioh's default ``OnDeltaImprovement`` trigger logs them — the
first evaluation, then every evaluation better than the last one written by more than 1e-10,
and the last evaluation of the run (with its own value) if it was not written already.
``raw_y`` is the precision ``f - f_opt`` (what ioh writes for BBOB), printed ``%.10f``.

:func:`merge` gathers per-run folders into one folder per algorithm (one ``.json`` per function,
one ``.dat`` per dimension holding every run), the layout one Analyzer writes for a whole
experiment; IOHanalyzer reads either (it scans folders recursively), but keeps only the first
of several files whose runs share algorithm, function, dimension and instances, so merge runs
that repeat an instance with other seeds before uploading them.

Where this differs from ioh (0.3.22): a NaN/inf value counts as an evaluation, as in ioh, but
is never written: ioh writes a non-finite first or last evaluation as a row (``nan``, ``None``
for inf); here it is never an improvement, and the last line of a run whose last value is not
finite carries the best value instead. Functions of ``tcbench/<Name>-v0`` get ids 101, 102, ...
in the order of :data:`tcbench.tasks.FUNCTIONS` (BBOB keeps 1-24) and their instance is the run
seed (which draws the instance when ``shift=true``).

ioh's own ``Analyzer`` is not used (benchmarks/RESULTS.md, ``ioh_writer_vs_analyzer.py``): it
logs only what passes through an ioh problem, and tcbench's functions through
``ioh.wrap_problem`` take 18.6x the time, with ioh's function ids; it writes in place, into
``<folder>-1`` when the folder exists; and ioh reads and merges nothing. On BBOB, where both
log, the ``.dat`` files are identical (``tests/test_bbob.py``).
"""

from __future__ import annotations

import json
import os
import shutil
from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

DELTA = 1e-10  # ioh.logger.trigger.OnDeltaImprovement's default
HEADER = "evaluations raw_y"
ATTRIBUTES = ["evaluations", "raw_y"]
TCBENCH_FUNCTION_ID_OFFSET = 100


class IOHFormatError(ValueError):
    """An IOHprofiler folder that does not parse: names the file and what is wrong."""


def format_version() -> str:
    """The IOHprofiler format version written: the installed ioh's (whose Analyzer this mirrors)."""
    try:
        return version("ioh")
    except PackageNotFoundError:
        return "0.3.22"


@dataclass(frozen=True)
class ProblemMeta:
    """Which problem a run solved, as IOHprofiler names it."""

    suite: str
    function_id: int
    function_name: str
    dim: int
    instance: int


def problem_meta(env: Any, seed: int) -> ProblemMeta:
    """IOHprofiler names of a BBOB task or a ``tcbench/<Name>-v0`` function task."""
    from tcbench.tasks import FUNCTIONS
    from tcbench.tasks.bbob_env import BBOBEnv

    if isinstance(env, BBOBEnv):
        return ProblemMeta("BBOB", env.function_id, env.function_name, env.dim, env.instance)
    key = getattr(getattr(env, "function", None), "key", None)
    if key not in FUNCTIONS or getattr(env, "n_objectives", 1) != 1:
        raise ValueError(f"no IOHprofiler log for {type(env).__name__}: single-objective function tasks only")
    fid = TCBENCH_FUNCTION_ID_OFFSET + list(FUNCTIONS).index(key) + 1
    return ProblemMeta("tcbench", fid, key.capitalize(), env.dim, int(seed))


@dataclass
class IOHRun:
    """One run: its problem, algorithm, the rows of its ``.dat`` block and its summary."""

    meta: ProblemMeta
    algorithm: str
    algorithm_info: str
    evaluations: np.ndarray  # (rows,) int: evaluation count of each written row
    raw_y: np.ndarray  # (rows,) precision written on each row
    evals: int  # evaluations used by the run
    best_evals: int
    best_y: float
    best_x: list[float]
    seed: int | None = None
    attributes: dict[str, str] = field(default_factory=dict)

    def best_so_far(self) -> np.ndarray:
        """Best precision so far at each row (the last row may be worse than the best)."""
        return np.minimum.accumulate(self.raw_y)


class RunLogger:
    """Collects one run's improvements batch by batch (:meth:`record`) and writes the run into
    ``folder`` at :meth:`close` (atomically: a killed run leaves no half-written folder)."""

    def __init__(self, folder: Path | str, meta: ProblemMeta, algorithm: str, algorithm_info: str = "",
                 seed: int | None = None, attributes: dict[str, Any] | None = None, delta: float = DELTA) -> None:
        self.folder = Path(folder)
        self.meta, self.algorithm, self.algorithm_info = meta, str(algorithm), str(algorithm_info)
        self.seed = seed
        self.attributes = {str(k): str(v) for k, v in (attributes or {}).items()}
        self.delta = float(delta)
        self.rows_evals: list[int] = []
        self.rows_y: list[float] = []
        self.reference = np.inf  # last value written
        self.minimum = np.inf  # best value seen (written or not)
        self.best_x: list[float] = []
        self.best_evals = 0
        self.evaluations = 0
        self.last_y = np.nan

    def record(self, x: np.ndarray, y: np.ndarray) -> None:
        """One evaluated batch: points ``x`` ``(n, d)`` and their precisions ``y`` ``(n,)``."""
        y = np.asarray(y, dtype=np.float64).reshape(-1)
        if y.size:
            ranked = np.where(np.isfinite(y), y, np.inf)
            low = float(ranked.min())
            if low < self.minimum:
                before = np.minimum.accumulate(np.concatenate(([self.minimum], ranked)))[:-1]
                # Only a new strict minimum can beat the last written value by more than delta.
                for i in np.flatnonzero(ranked < before):
                    if ranked[i] < self.reference - self.delta:
                        self.reference = float(ranked[i])
                        self.rows_evals.append(self.evaluations + int(i) + 1)
                        self.rows_y.append(self.reference)
                        self.best_evals, self.best_x = self.rows_evals[-1], np.asarray(x[i], dtype=float).tolist()
                self.minimum = low
            self.last_y = float(y[-1])
        self.evaluations += y.size

    def run(self) -> IOHRun:
        """The run as recorded so far, with its closing row."""
        evals, ys = list(self.rows_evals), list(self.rows_y)
        if self.evaluations and (not evals or evals[-1] != self.evaluations):
            evals.append(self.evaluations)
            ys.append(self.last_y if np.isfinite(self.last_y) else self.reference)
        return IOHRun(self.meta, self.algorithm, self.algorithm_info, np.asarray(evals, dtype=np.int64),
                      np.asarray(ys, dtype=np.float64), self.evaluations, self.best_evals, self.reference,
                      self.best_x, self.seed, dict(self.attributes))

    def close(self) -> list[Path]:
        """Write the run (replacing an earlier run in the same folder); the files written."""
        tmp = self.folder.with_name(f".{self.folder.name}.tmp-{os.getpid()}")
        shutil.rmtree(tmp, ignore_errors=True)
        written = write_runs(tmp, [self.run()])
        old = self.folder.with_name(f".{self.folder.name}.old-{os.getpid()}")
        if self.folder.exists():
            self.folder.rename(old)
        tmp.rename(self.folder)
        shutil.rmtree(old, ignore_errors=True)
        return [self.folder / p.relative_to(tmp) for p in written]


def _stem(meta: ProblemMeta) -> str:
    return f"f{meta.function_id}_{meta.function_name}"


def write_runs(folder: Path, runs: list[IOHRun]) -> list[Path]:
    """Write runs of one algorithm into ``folder``: one ``.json`` per function, one ``.dat`` per
    function and dimension (runs in the order given); the paths written."""
    folder.mkdir(parents=True, exist_ok=True)
    by_function: dict[tuple[str, int, str], list[IOHRun]] = defaultdict(list)
    for r in runs:
        by_function[(r.meta.suite, r.meta.function_id, r.meta.function_name)].append(r)
    written = []
    for (suite, fid, fname), group in by_function.items():
        algorithms = {(r.algorithm, r.algorithm_info) for r in group}
        if len({a for a, _ in algorithms}) != 1:
            raise ValueError(f"one algorithm per IOHprofiler file, got {sorted(a for a, _ in algorithms)}")
        stem = _stem(group[0].meta)
        scenarios = []
        for dim in sorted({r.meta.dim for r in group}):
            in_dim = [r for r in group if r.meta.dim == dim]
            dat = folder / f"data_{stem}" / f"IOHprofiler_f{fid}_DIM{dim}.dat"
            dat.parent.mkdir(parents=True, exist_ok=True)
            lines = []
            for r in in_dim:
                lines.append(HEADER)
                lines += [f"{e} {y:.10f}" for e, y in zip(r.evaluations.tolist(), r.raw_y.tolist(), strict=True)]
            dat.write_text("\n".join(lines) + "\n")
            written.append(dat)
            scenarios.append({"dimension": dim, "path": dat.relative_to(folder).as_posix(), "runs": [
                {"instance": r.meta.instance, "evals": r.evals,
                 "best": {"evals": r.best_evals, "y": r.best_y if np.isfinite(r.best_y) else None, "x": r.best_x}}
                | ({"seed": r.seed} if r.seed is not None else {})
                for r in in_dim
            ]})
        shared = dict(set.intersection(*(set(r.attributes.items()) for r in group)))
        meta = {
            "version": format_version(), "suite": suite, "function_id": fid, "function_name": fname,
            "maximization": False,
            "algorithm": {"name": group[0].algorithm, "info": "; ".join(sorted({i for _, i in algorithms}))},
            "experiment_attributes": [{k: shared[k]} for k in sorted(shared)],
            **({"run_attributes": ["seed"]} if all(r.seed is not None for r in group) else {}),
            "attributes": ATTRIBUTES, "scenarios": scenarios,
        }
        path = folder / f"IOHprofiler_{stem}.json"
        path.write_text(json.dumps(meta, indent="\t") + "\n")
        written.append(path)
    return written


def _read_dat(path: Path) -> list[np.ndarray]:
    """The blocks of a ``.dat`` file, each ``(rows, 2)`` [evaluations, raw_y]."""
    if not path.is_file():
        raise IOHFormatError(f"{path}: data file missing")
    blocks: list[list[list[float]]] = []
    for n, line in enumerate(path.read_text().splitlines(), start=1):
        if line.strip() == HEADER:
            blocks.append([])
            continue
        fields = line.split()
        if not blocks or len(fields) != 2:
            raise IOHFormatError(f"{path}:{n}: expected '{HEADER}' or two numbers, got {line!r}")
        try:
            blocks[-1].append([int(fields[0]), float(fields[1])])
        except ValueError:
            raise IOHFormatError(f"{path}:{n}: not an evaluation count and a value: {line!r}") from None
    return [np.asarray(b, dtype=np.float64).reshape(-1, 2) for b in blocks]


def read_json(path: Path) -> list[IOHRun]:
    """The runs of one IOHprofiler ``.json`` and its ``.dat`` files, checked for consistency."""
    try:
        meta = json.loads(path.read_text())
        suite, fid, fname = str(meta["suite"]), int(meta["function_id"]), str(meta["function_name"])
        algorithm = meta["algorithm"]
        if meta["attributes"] != ATTRIBUTES or meta["maximization"] is not False:
            raise IOHFormatError(f"{path}: expected attributes {ATTRIBUTES} and minimisation")
        shared = {k: str(v) for item in meta.get("experiment_attributes", []) for k, v in item.items()}
        runs = []
        for sc in meta["scenarios"]:
            blocks = _read_dat(path.parent / sc["path"])
            if len(blocks) != len(sc["runs"]):
                raise IOHFormatError(f"{path}: {len(sc['runs'])} runs in dimension {sc['dimension']} but "
                                     f"{len(blocks)} blocks in {sc['path']}")
            for r, b in zip(sc["runs"], blocks, strict=True):
                ev = b[:, 0].astype(np.int64)
                if ev.size == 0 or ev[0] < 1 or np.any(np.diff(ev) <= 0) or ev[-1] != int(r["evals"]):
                    raise IOHFormatError(f"{path}: a run's evaluations in {sc['path']} are not increasing "
                                         f"from >= 1 to its evals ({r['evals']})")
                m = ProblemMeta(suite, fid, fname, int(sc["dimension"]), int(r["instance"]))
                best = r["best"]
                runs.append(IOHRun(m, str(algorithm["name"]), str(algorithm.get("info", "")), ev, b[:, 1],
                                   int(r["evals"]), int(best["evals"]),
                                   float("inf") if best["y"] is None else float(best["y"]),
                                   [float(v) for v in best["x"]], r.get("seed"), dict(shared)))
        return runs
    except (KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, IOHFormatError):
            raise
        raise IOHFormatError(f"{path}: {type(exc).__name__}: {exc}") from None


def index_files(root: Path | str) -> list[Path]:
    """Every IOHprofiler ``.json`` under ``root`` (recursively; hidden folders skipped)."""
    root = Path(root)
    return sorted(p for p in root.rglob("IOHprofiler_*.json")
                  if not any(part.startswith(".") for part in p.relative_to(root).parts))


def read_runs(root: Path | str) -> list[IOHRun]:
    """Every run written under ``root``."""
    return [run for path in index_files(root) for run in read_json(path)]


def merge(root: Path | str, out: Path | str) -> list[Path]:
    """Gather the runs under ``root`` into ``out/<algorithm>/`` (see :func:`write_merged`)."""
    return write_merged(read_runs(root), out)


def write_merged(runs: Iterable[IOHRun], out: Path | str) -> list[Path]:
    """Write ``runs`` into ``out/<algorithm>/`` (one ``.json`` per function, one ``.dat`` per
    dimension), ordered by dimension, instance and seed; the files written."""
    by_algorithm: dict[str, list[IOHRun]] = defaultdict(list)
    for run in runs:
        by_algorithm[run.algorithm].append(run)
    written = []
    for algorithm, group in sorted(by_algorithm.items()):
        group.sort(key=lambda r: (r.meta.function_id, r.meta.dim, r.meta.instance, r.seed or 0))
        written += write_runs(Path(out) / algorithm.replace(os.sep, "_"), group)
    return written
