"""What ``tcbench calibrate`` does: cut a static recording into parts — its temperature branches,
or with ``blocks=N`` time blocks (:mod:`tcbench.signal.branches`) —, fit each offset model
(:mod:`tcbench.compensation.calibration`) on the training parts, score it on every part (and on
every part of ``test_recordings``), and write the board (``calibration.md`` and ``.csv``), the
residual plots and, for a kind PX4 calibrates (gyro, accel), PX4's ``TC_G*`` or ``TC_A*``
parameters of the cubic."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tcbench.commands.errors import CommandError, cannot_write, checked_store, read_recording_arg, writable_folder
from tcbench.commands.schemas import CalibrateConfig
from tcbench.staging import InputOverwriteError, moved, staged_dir


@dataclass
class CalibrationOutcome:
    """The board (one row per method and branch), the files written, the recording's sensor."""

    table: Any
    written: dict[str, Path]
    sensor: str


def check_calibrate(cfg: CalibrateConfig) -> tuple[Any, list[Any], list[tuple[str, Any, list[Any]]]]:
    """Every argument before any work: the recording (read and validated), its branches and the
    training ones among them, the methods, and each of ``test_recordings`` with its parts (same
    kind and unit as the recording)."""
    from tcbench.compensation.calibration import METHODS

    if not cfg.recording:
        raise CommandError("recording=PATH is required")
    if unknown := [m for m in cfg.methods if m not in METHODS]:
        raise CommandError(f"methods: unknown {unknown[0]!r}; known: {', '.join(METHODS)}")
    if not cfg.methods:
        raise CommandError("methods: give at least one (known: " + ", ".join(METHODS) + ")")
    if not (cfg.min_swing_c > 0 and cfg.drift_window_s > 0):
        raise CommandError("min_swing_c and drift_window_s must be > 0")
    if cfg.seed < 0:
        raise CommandError(f"seed must be a non-negative integer, got {cfg.seed}")
    if not 1 <= cfg.restarts <= 1000:
        raise CommandError(f"restarts must be 1..1000, got {cfg.restarts}")
    if not 0 <= cfg.px4_instance <= 3:
        raise CommandError(f"px4_instance must be 0..3, got {cfg.px4_instance}")
    writable_folder(cfg.out)
    checked_store(cfg.tracking)
    rec, branches, (parts, how) = _prepared(cfg.recording, cfg)
    bad = [k for k in cfg.train_branches if not 0 <= k < len(branches)]
    if bad or not cfg.train_branches:
        raise CommandError(f"train_branches={list(cfg.train_branches)}: the recording has {len(branches)} "
                           f"{parts} (0..{len(branches) - 1}; {how})")
    others = []
    for path in cfg.test_recordings:
        other, other_parts, _ = _prepared(path, cfg)
        if (other.meta.sensor, other.meta.units.get("output")) != (rec.meta.sensor, rec.meta.units.get("output")):
            raise CommandError(f"test_recordings: {path} records {other.meta.sensor} output in "
                               f"{other.meta.units.get('output')}, not {rec.meta.sensor} output in "
                               f"{rec.meta.units.get('output')} like {cfg.recording}")
        if Path(path).stem == Path(cfg.recording).stem or Path(path).stem in {Path(p).stem for p, *_ in others}:
            raise CommandError(f"test_recordings: two recordings named {Path(path).stem!r}; rename one")
        others.append((str(path), other, other_parts))
    return rec, branches, others


def _prepared(path: str, cfg: CalibrateConfig) -> tuple[Any, list[Any], tuple[str, str]]:
    """A recording read (``true_input`` applied) and cut into its parts: temperature branches, or
    ``blocks`` time blocks; with the parts' name and how they were cut, for messages."""
    from tcbench.signal.branches import temperature_branches, time_blocks

    rec = read_recording_arg(path)
    if cfg.true_input is not None:
        rec.data["input"] = true_input(cfg.true_input, rec.meta.units.get("input", ""))
    if cfg.blocks is None:
        branches = temperature_branches(rec.time_s, rec.temperature_c, cfg.min_swing_c)
        return rec, branches, (f"temperature branch{'es' * (len(branches) != 1)}", f"min_swing_c={cfg.min_swing_c:g} degC")
    try:
        branches = time_blocks(rec.time_s, rec.temperature_c, cfg.blocks)
    except ValueError as exc:
        raise CommandError(f"blocks={cfg.blocks}: {exc}") from None
    return rec, branches, (f"time block{'s' * (len(branches) != 1)}", f"blocks={cfg.blocks}")


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
    """Fit, score and write; print the board."""
    import pandas as pd

    from tcbench.compensation.calibration import LEARNERS, fit, from_model, record, residual, scores
    from tcbench.tables import markdown_table

    rec, branches, others = check_calibrate(cfg)
    unit = rec.meta.units.get("output", "")
    whole = record(rec.time_s, rec.temperature_c, rec.output, rec.input)
    train = [whole.part(branches[k].start, branches[k].stop) for k in cfg.train_branches]
    diagnosis = _diagnosed(rec, branches, cfg) if "model" in cfg.methods else None
    fitted = {m: [from_model(diagnosis[1])] if m == "model" else  # type: ignore[index]
              [fit(m, train, cfg.seed + r) for r in range(cfg.restarts if m in LEARNERS else 1)]
              for m in dict.fromkeys(cfg.methods)}
    rows: list[dict[str, Any]] = []
    residuals = {}
    for path, r, parts in [(cfg.recording, rec, branches), *others]:
        own = r is rec
        target = whole if own else record(r.time_s, r.temperature_c, r.output, r.input)
        every = {m: [residual(model, target) for model in runs] for m, runs in fitted.items()}
        for m, runs in every.items():
            for k, b in enumerate(parts):
                s = [scores(res[b.start:b.stop], r.time_s[b.start:b.stop], cfg.drift_window_s) for res in runs]
                rows.append({"recording": Path(path).stem, "method": m, "branch": k, "direction": b.direction,
                             "from_c": b.from_c, "to_c": b.to_c,
                             "role": "train" if own and k in cfg.train_branches else "test",
                             f"drift_rms_{_slug(unit)}": float(np.median([x["drift_rms"] for x in s])),
                             f"rms_{_slug(unit)}": float(np.median([x["rms"] for x in s])),
                             "restarts": len(runs)})
        if own:
            residuals = {m: runs[0] for m, runs in every.items()}
    models = {m: runs[0] for m, runs in fitted.items()}
    table = pd.DataFrame(rows)
    out = Path(cfg.out)
    try:
        with staged_dir(out, [Path(cfg.recording), *map(Path, cfg.test_recordings)]) as tmp:
            written = _write(tmp, cfg, rec, branches, models, residuals, table, unit)
            if diagnosis is not None:
                from tcbench.diagnose.report import write_report

                report = write_report(diagnosis[0], tmp / "diagnosis", with_plots=False)
                written |= {f"diagnosis {k}": v for k, v in report.items()}
    except InputOverwriteError as exc:
        raise CommandError(f"the output {exc.target} would overwrite the input {exc.source}; choose another out=") \
            from None
    except OSError as exc:
        raise cannot_write(out, exc, "the calibration") from None
    written = moved(written, tmp, out)
    print(f"\ncalibration of {Path(cfg.recording).name} ({rec.meta.sensor}, {unit}): fitted on branch"
          f"{'es' * (len(cfg.train_branches) > 1)} {', '.join(map(str, cfg.train_branches))}, "
          f"drift = RMS of the residual's {cfg.drift_window_s:g}-s running mean\n")
    print(markdown_table(table))
    print(f"\nwritten: {', '.join(str(p) for p in written.values())}")
    return CalibrationOutcome(table, written, str(rec.meta.sensor))


def _diagnosed(rec: Any, branches: list[Any], cfg: CalibrateConfig) -> tuple[Any, Any]:
    """``tcbench diagnose`` on the training parts (their rows, in time order, gaps between them
    kept as gaps) and the model it fitted, for the ``model`` method. The parts may be shorter
    than a diagnosis of its own asks (30 min): down to five cross-validation folds of two
    thermometer-smoothing windows each (20 min)."""
    from tcbench.diagnose.diagnosis import diagnose
    from tcbench.diagnose.model_file import to_sensor_model
    from tcbench.diagnose.nonmean import DEFAULT_SMOOTH_S
    from tcbench.diagnose.plan import FOLDS
    from tcbench.diagnose.report import model_spec
    from tcbench.diagnose.signals import DiagnosisDataError
    from tcbench.sensors.recording import make_recording

    rows = np.concatenate([np.arange(branches[k].start, branches[k].stop) for k in sorted(set(cfg.train_branches))])
    part = make_recording(rec.time_s[rows], rec.temperature_c[rows], rec.input[rows], rec.output[rows],
                          sensor=rec.meta.sensor, sample_rate_hz=rec.meta.sample_rate_hz, device_id=rec.meta.device_id)
    try:
        diag = diagnose(part, name=f"{Path(cfg.recording).name} (training parts)",
                        min_duration_s=FOLDS * 2 * DEFAULT_SMOOTH_S)
    except DiagnosisDataError as exc:
        raise CommandError(f"methods: model: the training parts cannot be diagnosed ({exc}); fit on more parts, "
                           "or leave model out of methods") from None
    return diag, to_sensor_model(model_spec(diag))


def _slug(unit: str) -> str:
    return unit.replace("/", "_per_").replace(" ", "") or "unit"


def _write(tmp: Path, cfg: CalibrateConfig, rec: Any, branches: list[Any], models: dict[str, Any],
           residuals: dict[str, np.ndarray], table: Any, unit: str) -> dict[str, Path]:
    from tcbench.compensation.px4 import px4_covers, px4_factor, px4_parameters, write_parameters
    from tcbench.tables import markdown_table

    written = {"csv": tmp / "calibration.csv", "md": tmp / "calibration.md"}
    table.to_csv(written["csv"], index=False)
    test = table[table["role"] == "test"]
    note = ("" if len(test) else "\nEvery branch was used to fit: the scores are in-sample only.\n")
    parts = (f"{len(branches)} temperature branches (turning points standing out by {cfg.min_swing_c:g} degC)"
             if cfg.blocks is None else f"{len(branches)} time blocks of equal duration")
    about = [f"{rec.meta.sensor} recording, output in {unit}; {parts}; fitted on part(s) "
             f"{', '.join(map(str, cfg.train_branches))}, scored on every part.",
             f"drift = RMS of the residual's {cfg.drift_window_s:g}-s running mean (output minus true input minus "
             "the model's offset); rms = RMS of the residual."]
    if cfg.test_recordings:
        about.append(f"Also scored on every part of {', '.join(map(str, cfg.test_recordings))}.")
    if cfg.restarts > 1:
        about.append(f"The networks (bp, elman) are {cfg.restarts} restarts each (seeds {cfg.seed}.."
                     f"{cfg.seed + cfg.restarts - 1}): their median; the plot shows seed {cfg.seed}.")
    written["md"].write_text(f"# Calibration of {Path(cfg.recording).name}\n\n{' '.join(about)}\n{note}\n"
                             f"{markdown_table(table)}\n\n![residuals](residuals.png)\n")
    written["png"] = _plot(tmp / "residuals.png", rec, branches, residuals, unit, cfg)
    cubic = models.get("poly3")
    if cubic is not None and px4_covers(rec.meta.sensor):
        sensor = rec.meta.sensor
        params = px4_parameters([cubic.cubic], sensor, cfg.px4_instance, to_px4_unit=px4_factor(sensor, unit))
        written["px4"] = write_parameters(params, tmp / "px4_tc_params.txt", sensor)
    return written


def _plot(path: Path, rec: Any, branches: list[Any], residuals: dict[str, np.ndarray], unit: str,
          cfg: CalibrateConfig) -> Path:
    """Residual against time and against temperature, per method, training branches shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_c) = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    t_min = (rec.time_s - rec.time_s[0]) / 60.0
    for k in cfg.train_branches:
        b = branches[k]
        ax_t.axvspan(t_min[b.start], t_min[b.stop - 1], color="0.9", zorder=0)
    for m, res in residuals.items():
        ax_t.plot(t_min, res, lw=0.7, label=m)
        ax_c.plot(rec.temperature_c, res, lw=0.5, label=m)
    ax_t.set(xlabel="time (min); shaded: fitted", ylabel=f"residual ({unit})", title=Path(cfg.recording).name)
    ax_c.set(xlabel="thermometer (degC)", ylabel=f"residual ({unit})", title="against temperature")
    ax_t.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
