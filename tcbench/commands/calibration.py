"""What ``tcbench calibrate`` does: cut a static recording into parts — its temperature branches,
or with ``blocks=N`` time blocks (:mod:`tcbench.signal.branches`) —, screen the training parts
(:mod:`tcbench.compensation.screening`: bursts, spikes, thermometer glitches dropped, reported),
fit each offset model
(:mod:`tcbench.compensation.calibration`) on the training parts, score it on every part (and on
every part of ``test_recordings``), rank the methods on the held-out parts with a block-bootstrap
interval on every ratio (:mod:`tcbench.compensation.holdout`; a best whose interval against the
next reaches 1 is a tie), say in one line when a method is worse than raw held out, and write the long table (``calibration.md`` and
``.csv``), the residual plots and ``calibration.json`` (the ranking, and the cubic refitted on the
whole record with its static level and the recording's sensor, unit, axis and device id, which
``tcbench export`` turns into PX4 and ArduPilot parameters, and under ``device`` the parameters of
every fitted method a device can run, which ``tcbench export formats=[c]`` writes as C; the last
lines print that command).

Something is always held out: with no ``train_branches=``, a record of several temperature
branches is fitted on the consecutive branches whose temperatures span what the others need
(:mod:`tcbench.compensation.fitted_span`: the held-out score judges interpolation) and scored on
the others; a record of one branch (a single cooling) is cut into five time blocks, fitted on
blocks 0, 2, 4 and scored on 1 and 3."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tcbench.commands.errors import (
    CommandError,
    checked_store,
    free_outputs,
    read_recording_arg,
    say_replaced,
    writable_folder,
    writing_errors,
)
from tcbench.commands.schemas import CalibrateConfig
from tcbench.errors import unknown_name
from tcbench.staging import moved, staged_dir


FILES = ("calibration.csv", "calibration.json", "calibration.md", "residuals.png")  # OUT/, checked before any work
AUTO_BLOCKS = 5  # a record of one temperature branch: five time blocks, the even ones fitted
FIT_COEFFICIENTS = 5  # the largest linear fit, poly3_rate: the cubic's four and the rate term
MIN_FIT_ROWS = FIT_COEFFICIENTS + 1  # more rows than coefficients: a residual is left to score
CUBIC_TEMPERATURES = 4  # distinct thermometer readings a cubic in the temperature needs
PLOT_POINTS = 4000  # points per line of the residual plot (a min/max envelope beyond)


@dataclass
class CalibrationOutcome:
    """The long table (one row per method and part), the held-out summary (one row per method),
    the files written, the recording's sensor and the summary as ``calibration.json`` holds it."""

    table: Any
    written: dict[str, Path]
    sensor: str
    summary: Any = None
    about: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Split:
    """How a recording is cut and which parts are fitted: ``parts`` in time order, the indices of
    the ``train`` ones, the parts' name (``temperature branch``, ``time block``) and how they were
    cut (for messages)."""

    parts: list[Any]
    train: list[int]
    noun: str
    how: str
    why: str = ""  # why these parts are fitted, when calibrate chose them

    @property
    def held_out(self) -> list[int]:
        return [k for k in range(len(self.parts)) if k not in self.train]

    @property
    def plural(self) -> str:
        """``temperature branches``, ``time blocks``."""
        return self.noun.replace("branch", "branches") if self.noun.endswith("branch") else self.noun + "s"

    def describe(self, ks: list[int]) -> str:
        """``temperature branch 0 (cooling 51.6 -> -17.5 degC)`` or ``time blocks 1, 3``."""
        if len(ks) == 1:
            b = self.parts[ks[0]]
            return f"{self.noun} {ks[0]} ({b.direction} {b.from_c:.1f} -> {b.to_c:.1f} degC)"
        return f"{self.plural} {', '.join(map(str, ks))}"


def check_calibrate(cfg: CalibrateConfig) -> tuple[Any, Split, list[tuple[str, Any, list[Any]]]]:
    """Every argument before any work: the recording (read and validated), how it is split and
    fitted, the methods, and each of ``test_recordings`` with its parts (same kind and unit as the
    recording)."""
    from tcbench.compensation.calibration import METHODS

    if not cfg.recording:
        raise CommandError("recording=PATH is required")
    if unknown := [m for m in cfg.methods if m not in METHODS]:
        raise CommandError(f"methods: {unknown_name('method', unknown[0], METHODS)}")
    if not cfg.methods:
        raise CommandError("methods: give at least one (known: " + ", ".join(METHODS) + ")")
    if not (cfg.min_swing_c > 0 and cfg.drift_window_s > 0):
        raise CommandError("min_swing_c and drift_window_s must be > 0")
    if cfg.seed < 0:
        raise CommandError(f"seed must be a non-negative integer, got {cfg.seed}")
    if not 1 <= cfg.restarts <= 1000:
        raise CommandError(f"restarts must be 1..1000, got {cfg.restarts}")
    if cfg.axis is not None and cfg.axis not in ("x", "y", "z"):
        raise CommandError(f"axis={cfg.axis}: the axes are x, y and z")
    writable_folder(cfg.out)
    free_outputs(cfg.out, list(FILES), cfg.overwrite,
                 folders=[f for m in dict.fromkeys(cfg.methods) if m in OWN_FITS for f in OWN_FITS[m].folders])
    checked_store(cfg.tracking)
    rec, split = _split(cfg.recording, cfg)
    others = []
    for path in cfg.test_recordings:
        other, other_split = _split(path, cfg, own=False)
        other_parts = other_split.parts
        if (other.meta.sensor, other.meta.units.get("output")) != (rec.meta.sensor, rec.meta.units.get("output")):
            raise CommandError(f"test_recordings: {path} records {other.meta.sensor} output in "
                               f"{other.meta.units.get('output')}, not {rec.meta.sensor} output in "
                               f"{rec.meta.units.get('output')} like {cfg.recording}")
        if Path(path).stem == Path(cfg.recording).stem or Path(path).stem in {Path(p).stem for p, *_ in others}:
            raise CommandError(f"test_recordings: two recordings named {Path(path).stem!r}; rename one")
        others.append((str(path), other, other_parts))
    return rec, split, others


def _split(path: str, cfg: CalibrateConfig, own: bool = True) -> tuple[Any, Split]:
    """A recording read (``true_input`` applied) and cut into its parts — temperature branches, or
    ``blocks`` time blocks, or five time blocks when it has one branch and nothing says which parts
    to fit — with the fitted ones (``own``: the recording calibrated; a test recording's are all
    held out)."""
    from tcbench.signal.branches import temperature_branches, time_blocks

    rec = read_recording_arg(path)
    _check_record(path, rec, cfg, own)
    if cfg.true_input is not None:
        rec.data["input"] = true_input(cfg.true_input, rec.meta.units.get("input", ""))
    blocks = cfg.blocks
    if blocks is None:
        parts = temperature_branches(rec.time_s, rec.temperature_c, cfg.min_swing_c)
        noun, how = "temperature branch", f"min_swing_c={cfg.min_swing_c:g} degC"
        if len(parts) == 1 and cfg.train_branches is None and own:
            blocks = min(AUTO_BLOCKS, rec.time_s.size)
    if blocks is not None:
        try:
            parts = time_blocks(rec.time_s, rec.temperature_c, blocks)
        except ValueError as exc:
            raise CommandError(f"blocks={blocks}: {exc}") from None
        noun, how = "time block", f"blocks={blocks}" + ("" if cfg.blocks else ", as the record has one temperature branch")
    if not own:
        return rec, Split(parts, [], noun, how)
    why = ""
    if cfg.train_branches is not None:
        train = sorted(set(cfg.train_branches))
    elif noun == "time block" or len(parts) == 1:
        train = list(range(0, len(parts), 2)) if len(parts) > 1 else [0]
    else:
        train, why = _spanning(rec.temperature_c, parts)
    bad = [k for k in train if not 0 <= k < len(parts)]
    if bad or not train:
        raise CommandError(f"train_branches={list(cfg.train_branches or [])}: the recording has {len(parts)} "
                           f"{noun}{'es' * (noun.endswith('branch') and len(parts) != 1)}"
                           f"{'s' * (noun.endswith('block') and len(parts) != 1)} (0..{len(parts) - 1}; {how})")
    split = Split(parts, train, noun, how, why)
    rows = np.concatenate([np.arange(parts[k].start, parts[k].stop) for k in train])
    fittable(rec.temperature_c[rows], f"{path}: the fitted parts ({split.describe(train)})")
    return rec, split


def _spanning(temp_c: np.ndarray, parts: list[Any]) -> tuple[list[int], str]:
    """The default fitted branches of a record of several, and why in words
    (:func:`~tcbench.compensation.fitted_span.spanning_parts`)."""
    from tcbench.compensation.fitted_span import beyond_share, spanning_parts

    choice = spanning_parts(temp_c, parts)
    first = "" if choice.train == [0] else f", against {beyond_share(temp_c, parts, [0]):.1%} fitted on branch 0"
    lo, hi = choice.fitted_c
    these = "these consecutive branches span" if len(choice.train) > 1 else "this branch spans"
    return choice.train, (f"why: {these} the held-out temperatures best ({lo:.1f}..{hi:.1f} degC): "
                          f"{choice.beyond_share:.1%} of the held-out samples lie beyond{first}; "
                          "train_branches= chooses")


def _check_record(path: str, rec: Any, cfg: CalibrateConfig, own: bool) -> None:
    """What a calibration needs of a recording before it is cut: its sidecar (the sensor kind
    and units), the rows of the fitted parts (:data:`MIN_FIT_ROWS`; a test recording: two, to
    be cut) and a duration that holds one drift window (``drift_window_s``)."""
    from tcbench.sensors.recording import sidecar_path

    where = path if own else f"test_recordings: {path}"
    if rec.meta.sensor is None:
        raise CommandError(f"{'' if own else 'test_recordings: '}{sidecar_path(path)}: no such file; calibrate reads "
                           "the sensor kind and units from the recording's sidecar (tcbench import writes one)")
    rows = rec.time_s.size
    if rows < (MIN_FIT_ROWS if own else 2):
        need = (f"its fitted parts need at least {MIN_FIT_ROWS} rows, more than the {FIT_COEFFICIENTS} coefficients "
                "of poly3_rate (a cubic in the temperature and a rate term)"
                if own else "a recording scored part by part needs at least 2")
        raise CommandError(f"{where}: {rows} row{'s' * (rows != 1)}; {need}")
    duration_s = float(rec.time_s[-1] - rec.time_s[0])
    if not cfg.drift_window_s <= duration_s:
        raise CommandError(f"drift_window_s={cfg.drift_window_s:g} is longer than {where} ({duration_s:.6g} s): the "
                           f"drift is a running mean over that window, which must fit in the record; give "
                           f"drift_window_s={duration_s:.6g} or less")


def fittable(temp_c: np.ndarray, where: str) -> None:
    """A :class:`CommandError` unless the samples ``temp_c`` can be fitted: at least
    :data:`MIN_FIT_ROWS` of them, at :data:`CUBIC_TEMPERATURES` distinct temperatures."""
    if temp_c.size < MIN_FIT_ROWS:
        raise CommandError(f"{where} hold {temp_c.size} rows; a calibration fits up to {FIT_COEFFICIENTS} "
                           f"coefficients (poly3_rate) and needs at least {MIN_FIT_ROWS} rows there: fit on more "
                           "parts (train_branches=)")
    distinct = np.unique(temp_c).size
    if distinct < CUBIC_TEMPERATURES:
        span = float(np.ptp(temp_c))
        raise CommandError(f"{where} read {distinct} distinct temperature{'s' * (distinct != 1)} ({span:g} degC "
                           f"apart); a cubic in the temperature needs at least {CUBIC_TEMPERATURES}: calibrate a "
                           "record over a temperature range")


def true_input(spec: object, input_unit: str) -> float:
    """``VALUE[:unit]`` (``-1:g``, ``-9.81:m/s^2``, ``0.5``) in the recording's input unit."""
    from tcbench.sensors.units import UnitError, conversion

    text = str(spec)
    value, _, unit = text.partition(":")
    unit = unit.strip() or input_unit
    try:
        number = float(value)
    except ValueError:
        raise CommandError(f"true_input={text}: expected VALUE[:unit], e.g. -1:g") from None
    try:
        converted = conversion(unit, input_unit).to_schema(np.float64(number))
    except UnitError as exc:
        raise CommandError(f"true_input={text}: {exc}") from None
    if not np.isfinite(converted):
        raise CommandError(f"true_input={text}: must be a finite number")
    return float(converted)


def calibrate_recording(cfg: CalibrateConfig) -> CalibrationOutcome:
    """Fit, score, rank and write; print what is fitted and scored first, the held-out ranking last:
    the stages :func:`_methods`, :func:`_announce`, :func:`_screened`, :func:`_fit_all`,
    :func:`_scored`, :func:`_summarised`, :func:`_staged` and :func:`_print_summary`."""
    from tcbench.compensation.calibration import record

    rec, split, others = check_calibrate(cfg)
    unit = rec.meta.units.get("output", "")
    methods = _methods(cfg, rec, split)
    own_hash = _announce(cfg, rec, split, others, methods, unit)
    whole = record(rec.time_s, rec.temperature_c, rec.output, rec.input)
    screening = _screened(cfg, split, whole)
    training = _Training(cfg, rec, split, screening)
    fitted, diagnosis = _fit_all(training, methods)
    scored = _scored(training, others, whole, fitted, unit)
    summary, about = _summarised(training, scored, whole, fitted, unit, own_hash)
    written = _staged(cfg, rec, split, scored, summary, about, unit, diagnosis)
    _print_summary(summary, about, unit, written)
    return CalibrationOutcome(scored.table, written, str(rec.meta.sensor), summary, about)


@dataclass(frozen=True)
class _Training:
    """What every fit of a calibration is given: the config, the recording, its split and the
    screening of its training parts."""

    cfg: CalibrateConfig
    rec: Any
    split: Split
    screening: Any  # tcbench.compensation.screening.Screening

    @property
    def starts_s(self) -> np.ndarray:
        """The training parts' first times (s): the memoriser's clocks."""
        return self.rec.time_s[[self.split.parts[k].start for k in self.split.train]]


@dataclass(frozen=True)
class OwnFit:
    """A method calibrate fits itself rather than through :func:`tcbench.compensation.calibration.fit`:
    ``fit`` gives its offset model and the diagnosis written beside the calibration (into the
    ``folders`` of OUT/, by :func:`_staged`); ``left_out`` says why a recording is too short for
    it (None: it is not)."""

    fit: Callable[[_Training], tuple[Any, Any]]
    left_out: Callable[[Any, Split], str | None]
    folders: tuple[str, ...] = ()


def _fit_diagnosed(training: _Training) -> tuple[Any, Any]:
    """The ``model`` method: ``tcbench diagnose`` on the screened training parts, its model as
    the offset; the diagnosis is written beside the calibration."""
    from tcbench.compensation.calibration import from_model

    diagnosis = _diagnosed(training.rec, training.split, training.cfg, training.screening.keep)
    return from_model(diagnosis[1]), diagnosis


def _fit_library(training: _Training, method: str, restart: int) -> Any:
    """A method of :data:`tcbench.compensation.calibration.FITTERS` fitted on the screened parts,
    a network's restart ``restart`` seeded ``seed + restart``."""
    from tcbench.compensation.calibration import fit

    return fit(method, training.screening.pieces, training.cfg.seed + restart, part_starts_s=training.starts_s)


def _methods(cfg: CalibrateConfig, rec: Any, split: Split) -> list[str]:
    """The methods to fit, once each in the order given, without those the recording is too short
    for (said in one line each)."""
    methods = list(dict.fromkeys(cfg.methods))
    for m in [m for m in methods if m in OWN_FITS]:
        if why := OWN_FITS[m].left_out(rec, split):
            methods.remove(m)
            print(f"tcbench: {m} left out: {why}", file=sys.stderr)
    return methods


def _announce(cfg: CalibrateConfig, rec: Any, split: Split, others: list[tuple[str, Any, list[Any]]],
              methods: list[str], unit: str) -> str:
    """Print what is fitted and scored, why these parts are fitted, and a warning when the scores
    are in-sample; the recording's content hash."""
    scored = split.describe(split.held_out) + " (held out)" if split.held_out else ""
    if cfg.test_recordings:
        scored += f"{' and ' if split.held_out else ''}every part of {', '.join(Path(p).name for p in cfg.test_recordings)}"
    print(f"calibrate {Path(cfg.recording).name} ({rec.meta.sensor}, output in {unit}): fitting {', '.join(methods)} on "
          f"{split.describe(split.train)}; scoring on {scored or 'the fitted parts only'}", flush=True)
    if split.why:
        print(f"  {split.why}", flush=True)
    if not split.held_out and not others:
        print("tcbench: warning: every part is fitted and no test_recordings= is given: the scores are "
              "in-sample and no method is ranked", file=sys.stderr)
    own_hash = _content_hash(cfg.recording)
    for path in (p for p in cfg.test_recordings if _content_hash(p) == own_hash):
        print(f"tcbench: warning: test_recordings: {path} holds the same data as {cfg.recording}: its scores are "
              "in-sample", file=sys.stderr)
    return own_hash


def _screened(cfg: CalibrateConfig, split: Split, whole: Any) -> Any:
    """The training parts of ``whole`` screened (:func:`tcbench.compensation.screening.screened_all`),
    said in one line; a :class:`CommandError` when screening leaves too little to fit."""
    from tcbench.compensation.screening import screened_all

    train = [whole.part(split.parts[k].start, split.parts[k].stop) for k in split.train]
    screening = screened_all(train, cfg.screen)
    print(screening.describe() if cfg.screen else "not screened (screen=false): " + screening.describe(), flush=True)
    if cfg.screen:
        fittable(np.concatenate([p.temp_c for p in screening.pieces] or [np.array([])]),
                 "the fitted parts left by screening (screen=false fits every sample)")
    return screening


def _fit_all(training: _Training, methods: list[str]) -> tuple[dict[str, list[Any]], Any]:
    """Every restart of every method fitted (a network ``restarts`` times, the others once), with a
    progress bar; and the diagnosis a method of :data:`OWN_FITS` made (None without one)."""
    from tqdm import tqdm

    from tcbench.compensation.calibration import LEARNERS

    jobs = [(m, r) for m in methods for r in range(training.cfg.restarts if m in LEARNERS else 1)]
    fitted: dict[str, list[Any]] = {m: [] for m in methods}
    diagnosis = None
    with tqdm(jobs, desc="fitting", unit="fit", leave=False, disable=None) as bar:
        for m, r in bar:
            bar.set_postfix_str(m)
            if m in OWN_FITS:
                model, diagnosis = OWN_FITS[m].fit(training)
            else:
                model = _fit_library(training, m, r)
            fitted[m].append(model)
    return fitted, diagnosis


@dataclass
class _Scores:
    """Every method scored on every part: the long table's rows, the calibrated recording's
    residual of each method (its first restart), and the held-out parts: each method's residuals
    (per restart), the raw residual, the temperatures, times, labels and sample steps (s)."""

    drift_key: str
    rows: list[dict[str, Any]] = field(default_factory=list)
    residuals: dict[str, np.ndarray] = field(default_factory=dict)
    held: dict[str, list[list[np.ndarray]]] = field(default_factory=dict)
    held_raw: list[np.ndarray] = field(default_factory=list)
    held_temp: list[np.ndarray] = field(default_factory=list)
    held_t: list[np.ndarray] = field(default_factory=list)
    held_labels: list[str] = field(default_factory=list)
    held_causal: dict[str, list[list[np.ndarray]]] = field(default_factory=dict)  # the Elman's and the model's streamed
    steps: list[float] = field(default_factory=list)
    table: Any = None  # the rows as a DataFrame


def _scored(training: _Training, others: list[tuple[str, Any, list[Any]]], whole: Any,
            fitted: dict[str, list[Any]], unit: str) -> _Scores:
    """Every restart of every method scored on every part of the recording and of each test
    recording (:func:`tcbench.compensation.calibration.scores`)."""
    import pandas as pd

    cfg, rec, split = training.cfg, training.rec, training.split
    out = _Scores(f"drift_rms_{_slug(unit)}", held={m: [[] for _ in runs] for m, runs in fitted.items()})
    for path, r, parts, fitted_parts in [(cfg.recording, rec, split.parts, split.train),
                                         *[(p, o, ps, []) for p, o, ps in others]]:
        _score_recording(out, cfg, path, r, parts, fitted_parts, whole if r is rec else None, fitted, unit)
    out.table = pd.DataFrame(out.rows)
    return out


def _score_recording(out: _Scores, cfg: CalibrateConfig, path: str, r: Any, parts: list[Any], fitted_parts: list[int],
                     whole: Any, fitted: dict[str, list[Any]], unit: str) -> None:
    """One recording's rows and held-out parts added to ``out`` (``whole``: the calibrated
    recording's record, whose residuals are plotted; None for a test recording)."""
    from tcbench.compensation.c_export import STREAMED, streamed_residual
    from tcbench.compensation.calibration import record, residual, scores

    rms_key = f"rms_{_slug(unit)}"
    target = whole if whole is not None else record(r.time_s, r.temperature_c, r.output, r.input)
    starts_s = r.time_s[[b.start for b in parts]]
    every = {m: [residual(model, target, starts_s) for model in runs] for m, runs in fitted.items()}
    causal = {m: [streamed_residual(model, target) for model in fitted[m]] for m in STREAMED if m in fitted}
    dt_s = float(np.median(np.diff(r.time_s))) if r.time_s.size > 1 else 1.0
    for k, b in enumerate(parts):
        held_out = k not in fitted_parts
        if held_out:
            out.steps.append(dt_s)
            out.held_raw.append((r.output - r.input)[b.start:b.stop])
            out.held_t.append(r.time_s[b.start:b.stop])
            out.held_temp.append(r.temperature_c[b.start:b.stop])
            out.held_labels.append(f"{Path(path).stem}:{k}")
        for m, runs in every.items():
            s = [scores(res[b.start:b.stop], r.time_s[b.start:b.stop], cfg.drift_window_s) for res in runs]
            if held_out:
                for i, res in enumerate(runs):
                    out.held[m][i].append(res[b.start:b.stop])
                for i, res in enumerate(causal.get(m, [])):
                    if res is not None:
                        out.held_causal.setdefault(m, [[] for _ in runs])[i].append(res[b.start:b.stop])
            out.rows.append({"recording": Path(path).stem, "method": m, "branch": k, "direction": b.direction,
                             "from_c": b.from_c, "to_c": b.to_c, "role": "test" if held_out else "train",
                             out.drift_key: float(np.median([x["drift_rms"] for x in s])),
                             rms_key: float(np.median([x["rms"] for x in s])), "restarts": len(runs)})
    if whole is not None:
        out.residuals = {m: runs[0] for m, runs in every.items()}


def _summarised(training: _Training, scored: _Scores, whole: Any, fitted: dict[str, list[Any]], unit: str,
                own_hash: str) -> tuple[Any, dict[str, Any]]:
    """The held-out summary (one row per method) and what ``calibration.json`` holds."""
    cfg, screening = training.cfg, training.screening
    summary, about = _ranked(scored.table, scored.held, scored.held_raw, scored.steps, cfg, unit, scored.drift_key)
    about["per_part"] = _per_part(scored.held, scored.held_raw, scored.steps, scored.held_labels, cfg)
    if scored.steps and scored.held_causal:
        about["streamed"] = _streamed_drift(scored.held_causal, scored.steps, cfg)
    about |= _floor(scored.held, scored.held_raw, scored.held_t, scored.steps, cfg)
    about |= _about(cfg, training.rec, training.split, unit, own_hash)
    about["screening"] = screening.as_dict() | {"line": screening.describe(), "enabled": cfg.screen}
    about["range"] = _range(screening.pieces, scored.held_temp)
    about["training"] = _training(fitted)
    about["export"] = _export_fit(whole, cfg.screen)
    about["device"] = _device_specs(fitted, training.rec.time_s)
    return summary, about


def _staged(cfg: CalibrateConfig, rec: Any, split: Split, scored: _Scores, summary: Any, about: dict[str, Any],
            unit: str, diagnosis: Any) -> dict[str, Path]:
    """Every file written into a staging folder, then moved into OUT/ all together (never over an
    input; what ``overwrite=true`` replaced said in one line); the files by key."""
    out = Path(cfg.out)
    replaced: list[Path] = []
    with writing_errors(out, "the calibration", overwrite_hint="out="):
        with staged_dir(out, [Path(cfg.recording), *map(Path, cfg.test_recordings)], cfg.overwrite, replaced) as tmp:
            written = _write(tmp, cfg, rec, split, scored.residuals, scored.table, summary, about, unit)
            if diagnosis is not None:
                from tcbench.diagnose.report.write import write_report

                report = write_report(diagnosis[0], tmp / "diagnosis", with_plots=False)
                written |= {f"diagnosis {k}": v for k, v in report.items()}
    written = moved(written, tmp, out)
    say_replaced(replaced)
    return written


def _ranked(table: Any, held: dict[str, list[list[np.ndarray]]], held_raw: list[np.ndarray], steps: list[float],
            cfg: CalibrateConfig, unit: str, drift_key: str) -> tuple[Any, dict[str, Any]]:
    """One row per method: its held-out drift and RMS (every held-out sample pooled; the networks'
    restarts averaged in the squares), its drift on the fitted parts, its ratio to the best's and
    to raw's drift, each with its block-bootstrap interval (``held_raw``: the raw residual of the
    held-out parts, scored even when ``raw`` is not among the methods); and the ranking: the best
    method, its margin over the next with its interval, the methods the interval cannot tell from
    the best (a tie), and those worse than raw."""
    import pandas as pd

    from tcbench.compensation.holdout import LEVEL, block_sums, ratio_interval

    fit_rows = table[(table["role"] == "train")]
    fit_drift = fit_rows.groupby("method", sort=False)[drift_key].apply(lambda x: float(np.sqrt(np.mean(x ** 2))))
    if not steps:
        summary = pd.DataFrame({"method": list(held), f"fit_drift_{_slug(unit)}": [fit_drift.get(m) for m in held]})
        return summary, {"held_out": False}
    runs = {f"{m}#{i}": parts for m, per in held.items() for i, parts in enumerate(per)} | {"raw-ref#0": held_raw}
    sums = block_sums(runs, steps, cfg.drift_window_s)
    squares = {m: np.mean([sums.squares[f"{m}#{i}"] for i in range(len(per))], axis=0) for m, per in held.items()}
    pooled = type(sums)(squares | {"raw-ref": sums.squares["raw-ref#0"]}, sums.counts, sums.block_s)
    rms = {m: float(np.sqrt(np.mean([np.mean(np.concatenate(parts) ** 2) for parts in per]))) for m, per in held.items()}
    order = sorted(held, key=lambda m: (np.isnan(pooled.drift(m)), pooled.drift(m)))
    best = order[0]
    to_best = {m: ratio_interval(pooled, m, best, seed=cfg.seed) for m in order}
    to_raw = {m: ratio_interval(pooled, m, "raw-ref", seed=cfg.seed) for m in order}
    summary = pd.DataFrame({
        "method": order,
        f"held_out_drift_{_slug(unit)}": [pooled.drift(m) for m in order],
        f"held_out_rms_{_slug(unit)}": [rms[m] for m in order],
        f"fit_drift_{_slug(unit)}": [float(fit_drift.get(m, np.nan)) for m in order],
        "x_best": [to_best[m][0] for m in order],
        "x_best_lo": [to_best[m][1] for m in order],
        "x_best_hi": [to_best[m][2] for m in order],
        "x_raw": [to_raw[m][0] for m in order],
        "x_raw_lo": [to_raw[m][1] for m in order],
        "x_raw_hi": [to_raw[m][2] for m in order],
    })
    ranking: dict[str, Any] = {"held_out": True, "best": best, "best_drift": pooled.drift(best),
                               "block_s": pooled.block_s, "blocks": int(pooled.counts.size), "level": LEVEL,
                               "drift": {m: pooled.drift(m) for m in order}, "raw_drift": pooled.drift("raw-ref"),
                               "x_raw": {m: list(to_raw[m]) for m in order},
                               "x_best": {m: list(to_best[m]) for m in order}}
    if len(order) > 1:
        point, lo, hi = ratio_interval(pooled, best, order[1], seed=cfg.seed)
        ranking |= {"next": order[1], "ratio_to_next": point, "ratio_lo": lo, "ratio_hi": hi,
                    "tied": [m for m in order[1:] if not to_best[m][1] > 1.0]}
    if best != "raw":
        ranking["ratio_to_raw"] = list(to_raw[best])
    ranking["worse_than_raw"], ranking["no_better_than_raw"] = raw_verdicts(to_raw)
    return summary, ranking


def _streamed_drift(causal: dict[str, list[list[np.ndarray]]], steps: list[float], cfg: CalibrateConfig
                    ) -> dict[str, Any]:
    """The held-out drift of the Elman and the diagnosed model as the exported C runs them (causal,
    from each record's first sample: :func:`~tcbench.compensation.c_export.streamed_residual`),
    pooled as the ranking pools calibrate's own, beside it in ``drift``."""
    from tcbench.compensation.holdout import block_sums

    runs = {f"{m}#{i}": parts for m, per in causal.items() for i, parts in enumerate(per)}
    sums = block_sums(runs, steps, cfg.drift_window_s)
    return {m: float(np.sqrt(np.mean([sums.squares[f"{m}#{i}"].sum() for i in range(len(per))]) / sums.counts.sum()))
            for m, per in causal.items()}


def _floor(held: dict[str, list[list[np.ndarray]]], held_raw: list[np.ndarray], held_t: list[np.ndarray],
           steps: list[float], cfg: CalibrateConfig) -> dict[str, Any]:
    """The white-noise floor of the held-out drift score and every method's drift over it, each
    with its block-bootstrap interval drawn within each held-out part (:func:`~tcbench.compensation.
    holdout.floor_intervals`): ``noise_floor`` ``[point, lo, hi]``, ``drift_over_parts`` (the RMS
    over the held-out parts of each part's drift, the median of the restarts: the long table's
    numbers) and ``x_floor`` ``{method: [point, lo, hi]}``; ``at_floor``: the methods whose
    interval reaches 1. Nothing when nothing is held out."""
    from tcbench.compensation.holdout import LEVEL, block_sums, floor_intervals, noise_sums

    if not steps:
        return {}
    runs = {f"{m}#{i}": parts for m, per in held.items() for i, parts in enumerate(per)}
    sums = block_sums(runs, steps, cfg.drift_window_s)
    noise = noise_sums(held_raw, held_t, steps, cfg.drift_window_s, sums.block_s)
    got = floor_intervals(sums, noise, {m: [f"{m}#{i}" for i in range(len(per))] for m, per in held.items()},
                          seed=cfg.seed)
    x_floor = {m: list(v) for m, v in got.x_floor.items()}
    return {"noise_floor": list(got.floor), "drift_over_parts": got.drift, "x_floor": x_floor,
            "at_floor": [m for m, (x, lo, _) in x_floor.items() if (lo <= 1.0 if lo == lo else x <= 1.0)],
            "floor_how": (f"white noise's drift score: the raw residual's sample variance (half that of its first "
                          f"differences, each block's slope, gaps and outliers left out) over the samples in one "
                          f"{cfg.drift_window_s:g}-s window; {LEVEL:.0%} block bootstrap within each held-out part, "
                          "every method on the same draws")}


def _floor_line(about: dict[str, Any], unit: str) -> str:
    """``White-noise floor 0.0011 [0.0009, 0.0013] deg/s; at the floor: ...`` in words."""
    point, lo, hi = about["noise_floor"]
    at = ", ".join(about["at_floor"]) or "none (every method's drift over the floor has its interval above 1)"
    return (f"White-noise floor of the drift score {point:.3g} [{lo:.3g}, {hi:.3g}] {unit} ({about['floor_how']}); "
            f"at the floor (the interval of the drift over it reaches 1): {at}.")


def raw_verdicts(to_raw: dict[str, tuple[float, float, float]]) -> tuple[list[str], list[str]]:
    """The methods worse than raw held out and those no better, from each one's drift ratio to
    raw's ``(point, lo, hi)``: a verdict is its interval's, not its point's — worse when the whole
    interval lies above 1, no better when it reaches 1 (``raw`` itself is neither)."""
    others = [m for m in to_raw if m != "raw"]
    worse = [m for m in others if to_raw[m][1] > 1.0]
    return worse, [m for m in others if m not in worse and not to_raw[m][2] < 1.0]


def _per_part(held: dict[str, list[list[np.ndarray]]], held_raw: list[np.ndarray], steps: list[float],
              labels: list[str], cfg: CalibrateConfig) -> list[dict[str, Any]]:
    """Each held-out part on its own (``recording:part``): every method's drift, its ratio to
    raw's and to the part's best with their block-bootstrap intervals, the best and its ties —
    the fit-on-one-run, test-on-another answer when the parts are runs."""
    from tcbench.compensation.holdout import block_sums, ratio_interval

    out = []
    for k, label in enumerate(labels):
        runs = {f"{m}#{i}": [per[i][k]] for m, per in held.items() for i in range(len(per))} | \
            {"raw-ref#0": [held_raw[k]]}
        sums = block_sums(runs, [steps[k]], cfg.drift_window_s)
        squares = {m: np.mean([sums.squares[f"{m}#{i}"] for i in range(len(per))], axis=0) for m, per in held.items()}
        pooled = type(sums)(squares | {"raw-ref": sums.squares["raw-ref#0"]}, sums.counts, sums.block_s)
        best = min(held, key=lambda m: pooled.drift(m))
        to_best = {m: list(ratio_interval(pooled, m, best, seed=cfg.seed)) for m in held}
        out.append({"part": label, "best": best, "blocks": int(sums.counts.size), "block_s": sums.block_s,
                    "drift": {m: pooled.drift(m) for m in held}, "raw_drift": pooled.drift("raw-ref"),
                    "x_raw": {m: list(ratio_interval(pooled, m, "raw-ref", seed=cfg.seed)) for m in held},
                    "x_best": to_best, "tied": [m for m in held if m != best and not to_best[m][1] > 1.0]})
    return out


def _training(fitted: dict[str, list[Any]]) -> dict[str, Any]:
    """How each fitted method was trained, one line each (the networks' algorithm, epochs and
    restarts; what the diagnosed model explains but does not compensate)."""
    from tcbench.compensation.fitted_model import dropped_terms
    from tcbench.compensation.training import describe

    out: dict[str, Any] = {}
    for m, runs in fitted.items():
        if runs and runs[0].training:
            out[m] = {"line": describe(m, [r.training for r in runs]), "runs": [r.training for r in runs]}
        elif runs and runs[0].sensor_model is not None:
            dropped = dropped_terms(runs[0].sensor_model)
            out[m] = {"line": "model: tcbench diagnose on the screened training parts (least squares); compensates "
                              "with its temperature terms only, not with "
                              + (", ".join(dropped) if dropped else "any clock-keyed term (none was fitted)")
                              + " (keyed to the calibration run's clock or its rig: explained, not compensated)",
                      "dropped": dropped}
    return out


def _range(pieces: list[Any], held_temp: list[np.ndarray]) -> dict[str, Any]:
    """The fitted temperatures and how far the held-out ones go beyond them (share of samples)."""
    lo = float(min(p.temp_c.min() for p in pieces))
    hi = float(max(p.temp_c.max() for p in pieces))
    out: dict[str, Any] = {"fitted_c": [lo, hi]}
    if held_temp:
        temp = np.concatenate(held_temp)
        out |= {"held_out_c": [float(temp.min()), float(temp.max())],
                "beyond_share": float(np.mean((temp < lo) | (temp > hi)))}
    return out


def _range_line(about: dict[str, Any]) -> str | None:
    """One line when held-out samples lie beyond the fitted temperatures: who is held at the edge."""
    r = about.get("range", {})
    if r.get("beyond_share", 0.0) < 0.001:
        return None
    (lo, hi), (hlo, hhi) = r["fitted_c"], r["held_out_c"]
    return (f"held out beyond the fitted {lo:.1f}..{hi:.1f} degC: {r['beyond_share']:.1%} of the samples "
            f"({hlo:.1f}..{hhi:.1f} degC); poly3, poly3_rate's cubic, bp and elman are held at the edge there "
            "(the networks' rate input too), poly3_rate's rate term and model carry on")


def _worse_lines(about: dict[str, Any]) -> list[str]:
    """One line when a method's held-out drift is above raw's with its whole interval (the
    calibration makes it worse), and one when its interval reaches 1 (no better than raw)."""
    def each(methods: list[str]) -> str:
        return ", ".join(f"{m} {about['x_raw'][m][0]:.2f}x [{about['x_raw'][m][1]:.2f}, {about['x_raw'][m][2]:.2f}]"
                         for m in methods)

    lines = []
    if worse := about.get("worse_than_raw") or []:
        lines.append(f"WORSE THAN RAW held out (drift over raw's, the whole interval above 1): {each(worse)}")
    if level := about.get("no_better_than_raw") or []:
        lines.append(f"no better than raw held out (the interval reaches 1): {each(level)}")
    return lines


def _about(cfg: CalibrateConfig, rec: Any, split: Split, unit: str, content_hash: str) -> dict[str, Any]:
    """What ``calibration.json`` says of the recording and the split."""
    from tcbench.sensors.recording import RecordingError, recording_axis

    source = rec.meta.extra.get("source", {}) if isinstance(rec.meta.extra, dict) else {}
    try:
        axis = cfg.axis or recording_axis(rec.meta)
    except RecordingError as exc:
        raise CommandError(f"{cfg.recording}: {exc}") from None
    return {"recording": Path(cfg.recording).name, "content_hash": content_hash,
            "sensor": rec.meta.sensor, "unit": unit, "axis": axis,
            "device_id": rec.meta.device_id, "px4_device_id": source.get("px4_device_id"),
            "parts": f"{len(split.parts)} {split.plural} ({split.how})", "fitted": split.train, "fitted_why": split.why,
            "held_out_parts": split.held_out, "test_recordings": [Path(p).name for p in cfg.test_recordings],
            "drift_window_s": cfg.drift_window_s}


def _content_hash(path: str) -> str:
    from tcbench.sensors.data_hash import content_hash

    return content_hash([path])


def _export_fit(whole: Any, screen: bool = True) -> dict[str, Any] | None:
    """The cubic an autopilot is given: ``poly3`` refitted on the whole record, screened as the
    training parts are (the held-out scores judged the method; the parameters use every kept
    sample), in the recording's output unit; and ``static_level``, the median of the offset it
    fits (the level PX4 leaves an accelerometer's ordinary calibration,
    :func:`tcbench.compensation.px4.px4_polynomial`)."""
    from tcbench.compensation.px4 import fit_offset
    from tcbench.compensation.screening import screen as screened

    kept = screened(whole, screen).pieces
    offset = np.concatenate([p.output - p.truth for p in kept])
    try:
        cubic = fit_offset(np.concatenate([p.temp_c for p in kept]), offset)
    except ValueError:
        return None
    return {"method": "poly3", "fitted_on": "the whole record" + (", screened" if screen else ""), "x": list(cubic.x),
            "tref_c": cubic.tref_c, "tmin_c": cubic.tmin_c, "tmax_c": cubic.tmax_c,
            "static_level": float(np.median(offset))}


def _device_specs(fitted: dict[str, list[Any]], t_s: np.ndarray) -> dict[str, Any]:
    """What ``tcbench export formats=[c]`` writes as C of each method a device can run
    (:func:`tcbench.compensation.c_export.device_spec`; a network's first restart, seed ``seed``,
    as the plot shows it), its rate ring sized to the record's fullest 120-s window."""
    from tcbench.compensation.c_export import EXPORTED, device_spec, window_samples

    fullest = window_samples(t_s)
    specs: dict[str, Any] = {}
    for m, runs in fitted.items():
        if m in EXPORTED and runs:
            try:
                specs[m] = device_spec(runs[0], fullest)
            except ValueError as exc:  # a diagnosed term no device runs: export says which
                specs.setdefault("_left_out", {})[m] = str(exc)
    return specs


def _print_summary(summary: Any, about: dict[str, Any], unit: str, written: dict[str, Path]) -> None:
    """The short table and the verdict, as the last lines a user reads."""
    from tcbench.tables import markdown_table

    print("\n" + markdown_table(summary.round(6)))
    print(f"\nlong table (every part): {written['md']}; residual plots: {written['png']}")
    if hint := _export_hint(about, Path(written["json"]).parent):
        print(hint)
    if [m for m in about.get("device", {}) if not m.startswith("_")]:
        import shlex

        folder = Path(written["json"]).parent
        print(f"as C for the sensor's own processor ({', '.join(m for m in about['device'] if not m.startswith('_'))}): "
              "tcbench export "
              f"{shlex.quote(f'calibrations=[{folder}]')} formats=[c]")
    if not about.get("held_out"):
        print("nothing held out: no method is ranked")
        return
    for line in (_range_line(about), *_worse_lines(about)):
        if line:
            print(line)
    print(_best_line(about, unit))
    apart = {m: v for m, v in about.get("streamed", {}).items() if f"{v:.3g}" != f"{about['drift'][m]:.3g}"}
    if apart:  # calibration.json keeps both always; the line only where they differ as printed
        print("as the device runs them (causal, the exported C): " + "; ".join(
            f"{m} {v:.3g} {unit} held out (calibrate's, reading ahead: {about['drift'][m]:.3g})"
            for m, v in apart.items()))


def _export_hint(about: dict[str, Any], folder: Path) -> str | None:
    """The ``tcbench export`` command of this calibration as it runs: with the device id the log
    gave; else for ArduPilot, and for PX4 with ``device_id=`` spelt out (PX4 applies ``TC_*``
    only to the sensor it names). None when neither autopilot calibrates the sensor kind."""
    import shlex

    from tcbench.compensation.px4 import px4_covers
    from tcbench.sensors import kinds

    sensor = about.get("sensor")
    if not about.get("export") or not px4_covers(sensor):
        return None
    command = f"tcbench export {shlex.quote(f'calibrations=[{folder}]')}"
    if about.get("axis") is None:
        return (f"for PX4/ArduPilot: the recording does not say its axis; calibrate again with axis=x|y|z, then "
                f"{command} ...")
    if about.get("px4_device_id") is not None:
        return f"for PX4/ArduPilot: {command} device_id={about['px4_device_id']}"
    cal = f"CAL_{kinds.get(sensor).px4_cal}0_ID"
    return (f"for ArduPilot: {command} formats=[ardupilot]\nfor PX4 too: {command} device_id=N, N the {sensor}'s "
            f"device id (its {cal} parameter on the vehicle, or the log's)")


def _best_line(about: dict[str, Any], unit: str) -> str:
    """``best held out: model, drift ...; 0.70x poly3's [0.55, 0.90] (...)``, or a tie."""
    line = f"best held out: {about['best']}, drift {about['best_drift']:.4g} {unit}"
    if "next" in about:
        line += (f"; {about['ratio_to_next']:.2f}x {about['next']}'s [{about['ratio_lo']:.2f}, "
                 f"{about['ratio_hi']:.2f}] ({about['level']:.0%} block bootstrap over {about['blocks']} "
                 f"blocks of {about['block_s']:.0f} s)")
        if about["tied"]:
            line += f": a tie with {', '.join(about['tied'])} (the interval reaches 1)"
    return line


def _too_short_to_diagnose(rec: Any, split: Split) -> str | None:
    """Why the fitted parts are too short for the ``model`` method's diagnosis, or None."""
    from tcbench.diagnose.select.plan import min_full_duration_s

    t = rec.time_s
    fitted_s = sum(float(t[split.parts[k].stop - 1] - t[split.parts[k].start]) for k in split.train)
    need_s = min_full_duration_s()
    if fitted_s >= need_s:
        return None
    return (f"the fitted parts last {fitted_s / 60:.1f} min and a diagnosis needs {need_s / 60:.0f} min "
            "(tcbench diagnose reports what a short record can tell)")


def _diagnosed(rec: Any, split: Split, cfg: CalibrateConfig, keep: np.ndarray | None = None) -> tuple[Any, Any]:
    """``tcbench diagnose`` on the training parts (their rows, in time order, gaps between them
    kept as gaps; ``keep``: the rows screening kept, per training row) and the model it fitted,
    for the ``model`` method. The parts must be as long as any full diagnosis
    (:func:`tcbench.diagnose.select.plan.min_full_duration_s`: 20 min); more rows than a diagnosis takes
    are diagnosed on bin means, their noise measured on every row (:mod:`tcbench.diagnose.rate.native_rate`,
    as ``tcbench diagnose`` does)."""
    from tcbench.diagnose.rate import native_rate
    from tcbench.diagnose.model_file import to_sensor_model
    from tcbench.diagnose.select.plan import min_full_duration_s
    from tcbench.diagnose.report.write import model_spec
    from tcbench.diagnose.signals import DiagnosisDataError
    from tcbench.sensors.recording import make_recording

    rows = np.concatenate([np.arange(split.parts[k].start, split.parts[k].stop) for k in split.train])
    if keep is not None:
        rows = rows[keep]
    part = make_recording(rec.time_s[rows], rec.temperature_c[rows], rec.input[rows], rec.output[rows],
                          sensor=rec.meta.sensor, sample_rate_hz=rec.meta.sample_rate_hz, device_id=rec.meta.device_id)
    try:
        diag = native_rate.diagnose_any_rate(part, name=f"{Path(cfg.recording).name} (training parts)",
                                             min_duration_s=min_full_duration_s())
    except DiagnosisDataError as exc:
        raise CommandError(f"methods: model: the training parts cannot be diagnosed ({exc}); fit on more parts, "
                           "or leave model out of methods") from None
    return diag, to_sensor_model(model_spec(diag))


# The methods calibrate fits itself (every other through tcbench.compensation.calibration.fit): the
# diagnosed model, which needs a full diagnosis's duration and writes the diagnosis into OUT/diagnosis/
OWN_FITS: dict[str, OwnFit] = {"model": OwnFit(_fit_diagnosed, _too_short_to_diagnose, ("diagnosis",))}


def _slug(unit: str) -> str:
    return unit.replace("/", "_per_").replace(" ", "") or "unit"


def _write(tmp: Path, cfg: CalibrateConfig, rec: Any, split: Split, residuals: dict[str, np.ndarray], table: Any,
           summary: Any, about: dict[str, Any], unit: str) -> dict[str, Path]:
    from tcbench.tables import markdown_table

    written = {"csv": tmp / "calibration.csv", "md": tmp / "calibration.md", "json": tmp / "calibration.json"}
    table.to_csv(written["csv"], index=False)
    note = "" if about.get("held_out") else "\nNothing was held out: the scores are in-sample only.\n"
    lines = [f"{rec.meta.sensor} recording, output in {unit}; {len(split.parts)} "
             f"{split.noun.replace('branch', 'branche')}s ({split.how}); "
             f"fitted on {split.describe(split.train)}{f' ({split.why})' if split.why else ''}, scored on every part.",
             f"drift = RMS of the residual's {cfg.drift_window_s:g}-s running mean (output minus true input minus "
             "the model's offset); rms = RMS of the residual."]
    if cfg.test_recordings:
        lines.append(f"Also scored on every part of {', '.join(map(str, cfg.test_recordings))}.")
    if cfg.restarts > 1:
        lines.append(f"The networks (bp, bp_gd, elman) are {cfg.restarts} restarts each (seeds {cfg.seed}.."
                     f"{cfg.seed + cfg.restarts - 1}): their median; the plot shows seed {cfg.seed}.")

    screening = about["screening"]
    lines.append(f"Training parts {'screened' if screening['enabled'] else 'not screened (screen=false)'} "
                 f"(tcbench.compensation.screening: departures beyond {screening['min_z']:g} robust sigmas or the "
                 f"Bonferroni bound from a {screening['window_s']:g}-s running median, widened by "
                 f"{screening['guard_s']:g} s; thermometer glitches; cut at gaps): "
                 f"{screening['line'].removeprefix('screened: ')}.")
    if about.get("training"):
        lines.append("\n\nTraining:\n\n" + "".join(f"- {t['line']}\n" for t in about["training"].values()))
    ranking = ""
    if about.get("held_out"):
        verdicts = [ln for ln in (_range_line(about), *_worse_lines(about)) if ln]
        ranking = (f"\n## Held out\n\nEvery held-out sample pooled; x_best = held-out drift over the best's, x_raw = "
                   f"over raw's, each with its {about['level']:.0%} block-bootstrap interval (_lo, _hi; "
                   f"{about['blocks']} blocks of {about['block_s']:g} s, every method on the same draws). "
                   + _best_line(about, unit).replace("best held out: ", "Best: ") + ".\n\n"
                   + "".join(f"- {v}\n" for v in verdicts) + ("\n" if verdicts else "")
                   + (_floor_line(about, unit) + "\n\n" if "noise_floor" in about else "")
                   + f"{markdown_table(summary.round(6))}\n")
    written["md"].write_text(f"# Calibration of {Path(cfg.recording).name}\n\n{' '.join(lines)}\n{note}{ranking}\n"
                             f"## Every part\n\n{markdown_table(table.drop(columns=['recording']) if not cfg.test_recordings else table)}"
                             "\n\n![residuals](residuals.png)\n")
    written["json"].write_text(json.dumps(about, indent=2, default=_plain) + "\n")
    written["png"] = _plot(tmp / "residuals.png", rec, split, residuals, unit, cfg)
    return written


def _plain(value: Any) -> Any:
    """numpy scalars and arrays as JSON numbers and lists."""
    return value.tolist() if hasattr(value, "tolist") else str(value)


def _envelope(x: np.ndarray, y: np.ndarray, points: int = PLOT_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """At most about ``points`` points of a long line, drawn as it would look: in each of
    ``points / 2`` runs of consecutive samples, the sample of the lowest and of the highest ``y``,
    in time order (a spike survives; the plot only, never a score)."""
    n = y.size
    per = -(-2 * n // points)  # samples per run, rounded up
    if per <= 2:
        return x, y
    runs = n // per
    head = np.arange(runs * per).reshape(runs, per)
    lo, hi = np.argmin(y[head], axis=1), np.argmax(y[head], axis=1)
    pick = np.sort(np.column_stack([head[np.arange(runs), lo], head[np.arange(runs), hi]]), axis=1).ravel()
    pick = np.concatenate([pick, np.arange(runs * per, n)])
    return x[pick], y[pick]


def _plot(path: Path, rec: Any, split: Split, residuals: dict[str, np.ndarray], unit: str,
          cfg: CalibrateConfig) -> Path:
    """Residual against time and against temperature, per method, training branches shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_c) = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    t_min = (rec.time_s - rec.time_s[0]) / 60.0
    for k in split.train:
        b = split.parts[k]
        ax_t.axvspan(t_min[b.start], t_min[b.stop - 1], color="0.9", zorder=0)
    for m, res in residuals.items():
        ax_t.plot(*_envelope(t_min, res), lw=0.7, label=m)
        ax_c.plot(*_envelope(rec.temperature_c, res), lw=0.5, label=m)
    ax_t.set(xlabel="time (min); shaded: fitted", ylabel=f"residual ({unit})", title=Path(cfg.recording).name)
    ax_c.set(xlabel="thermometer (degC)", ylabel=f"residual ({unit})", title="against temperature")
    ax_t.legend(fontsize=8, loc="upper left")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
