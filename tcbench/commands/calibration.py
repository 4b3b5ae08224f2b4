"""What ``tcbench calibrate`` does: split a static recording into its temperature branches
(:mod:`tcbench.signal.branches`), fit each offset model (:mod:`tcbench.compensation.calibration`)
on the training branches, score it on every branch, and write the board (``calibration.md`` and
``.csv``), the residual plots and, for a gyro, PX4's ``TC_G*`` parameters of the cubic."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tcbench.commands.errors import CommandError, cannot_write, checked_store, read_recording_arg, writable_folder
from tcbench.commands.schemas import CalibrateConfig
from tcbench.staging import InputOverwriteError, moved, staged_dir

UNITS_TO_PX4 = {"deg/s": np.pi / 180.0}  # the recording's unit -> PX4's (rad/s for sensor_gyro)


@dataclass
class CalibrationOutcome:
    """The board (one row per method and branch), the files written, the recording's sensor."""

    table: Any
    written: dict[str, Path]
    sensor: str


def check_calibrate(cfg: CalibrateConfig) -> tuple[Any, list[Any]]:
    """Every argument before any work: the recording (read and validated), its branches and the
    training ones among them, the methods."""
    from tcbench.compensation.calibration import METHODS
    from tcbench.signal.branches import temperature_branches

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
    if not 0 <= cfg.px4_instance <= 3:
        raise CommandError(f"px4_instance must be 0..3, got {cfg.px4_instance}")
    writable_folder(cfg.out)
    checked_store(cfg.tracking)
    rec = read_recording_arg(cfg.recording)
    branches = temperature_branches(rec.time_s, rec.temperature_c, cfg.min_swing_c)
    bad = [k for k in cfg.train_branches if not 0 <= k < len(branches)]
    if bad or not cfg.train_branches:
        raise CommandError(f"train_branches={list(cfg.train_branches)}: the recording has {len(branches)} "
                           f"temperature branch{'es' * (len(branches) != 1)} (0..{len(branches) - 1}; "
                           f"min_swing_c={cfg.min_swing_c:g} degC)")
    return rec, branches


def calibrate_recording(cfg: CalibrateConfig) -> CalibrationOutcome:
    """Fit, score and write; print the board."""
    import pandas as pd

    from tcbench.compensation.calibration import fit, record, residual, scores
    from tcbench.tables import markdown_table

    rec, branches = check_calibrate(cfg)
    unit = rec.meta.units.get("output", "")
    whole = record(rec.time_s, rec.temperature_c, rec.output, rec.input)
    train = [whole.part(branches[k].start, branches[k].stop) for k in cfg.train_branches]
    models = {m: fit(m, train, cfg.seed) for m in dict.fromkeys(cfg.methods)}
    residuals = {m: residual(model, whole) for m, model in models.items()}
    rows = []
    for m in models:
        for k, b in enumerate(branches):
            s = scores(residuals[m][b.start:b.stop], rec.time_s[b.start:b.stop], cfg.drift_window_s)
            rows.append({"method": m, "branch": k, "direction": b.direction, "from_c": b.from_c, "to_c": b.to_c,
                         "role": "train" if k in cfg.train_branches else "test",
                         f"drift_rms_{_slug(unit)}": s["drift_rms"], f"rms_{_slug(unit)}": s["rms"]})
    table = pd.DataFrame(rows)
    out = Path(cfg.out)
    try:
        with staged_dir(out, [Path(cfg.recording)]) as tmp:
            written = _write(tmp, cfg, rec, branches, models, residuals, table, unit)
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


def _slug(unit: str) -> str:
    return unit.replace("/", "_per_").replace(" ", "") or "unit"


def _write(tmp: Path, cfg: CalibrateConfig, rec: Any, branches: list[Any], models: dict[str, Any],
           residuals: dict[str, np.ndarray], table: Any, unit: str) -> dict[str, Path]:
    from tcbench.compensation.px4 import px4_parameters, write_parameters
    from tcbench.tables import markdown_table

    written = {"csv": tmp / "calibration.csv", "md": tmp / "calibration.md"}
    table.to_csv(written["csv"], index=False)
    test = table[table["role"] == "test"]
    note = ("" if len(test) else "\nEvery branch was used to fit: the scores are in-sample only.\n")
    written["md"].write_text(
        f"# Calibration of {Path(cfg.recording).name}\n\n"
        f"{rec.meta.sensor} recording, output in {unit}; {len(branches)} temperature branches "
        f"(turning points standing out by {cfg.min_swing_c:g} degC); fitted on branch(es) "
        f"{', '.join(map(str, cfg.train_branches))}, scored on every branch. drift = RMS of the residual's "
        f"{cfg.drift_window_s:g}-s running mean (output minus true input minus the model's offset); rms = RMS of "
        f"the residual.\n{note}\n{markdown_table(table)}\n\n![residuals](residuals.png)\n")
    written["png"] = _plot(tmp / "residuals.png", rec, branches, residuals, unit, cfg)
    cubic = models.get("poly3")
    if rec.meta.sensor == "gyro" and cubic is not None and unit in UNITS_TO_PX4:
        params = px4_parameters([cubic.cubic], "gyro", cfg.px4_instance, to_px4_unit=UNITS_TO_PX4[unit])
        written["px4"] = write_parameters(params, tmp / "px4_tc_params.txt")
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
