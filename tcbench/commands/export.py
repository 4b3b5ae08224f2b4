"""What ``tcbench export`` does: gather the calibrations of one IMU (``tcbench calibrate``'s
``calibration.json``, one per axis and sensor kind) and write the autopilots' parameter files,
every axis in its slot: PX4's ``TC_G<i>_*``/``TC_A<i>_*`` (:mod:`tcbench.compensation.px4`) and
ArduPilot's ``INS_TCAL<n>_*`` (:mod:`tcbench.compensation.ardupilot`); with ``formats=[c]``, C99
of every method the calibration fitted that a device can run, ``tc_<kind>_<axis>_<method>.h`` and
``.c`` each (:mod:`tcbench.compensation.c_export`).

The autopilots run a cubic only. Where a calibration's best held-out method is not the cubic, both
parameter files say so in a comment, and the command prints one line per axis with the cubic's
held-out drift against the best method's.

The axis of a calibration is the one its recording's sidecar names (``tcbench import axes=``, or
a PX4 log's field) or ``calibrate axis=``; a calibration without one is refused, as are two of one
axis. PX4 applies ``TC_<t><i>_*`` only to the sensor whose device id ``TC_<t><i>_ID`` names: it
comes from ``device_id=`` (one number, or ``{gyro: N, accel: M}``) or the log the recording was
imported from, and PX4's file is refused without one.

PX4 takes an accelerometer's polynomial without its static level (the median reading, gravity
included, as PX4's ``process_sensor_caldata.py`` fits it): that level stays in the reading for the
ordinary calibration ``CAL_ACCn_*``; a gyro's polynomial is its whole offset. ArduPilot's cubic
has no constant, so its file is the same either way.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tcbench.commands.errors import CommandError, free_outputs, say_replaced, writable_folder, writing_errors
from tcbench.commands.schemas import ExportConfig
from tcbench.errors import unknown_name
from tcbench.sensors import kinds
from tcbench.staging import moved, staged_dir

FORMATS = ("px4", "ardupilot", "c")
FILES = {"px4": "px4_tc_params.txt", "ardupilot": "ardupilot_tcal.parm"}  # the file of each format in OUT/
AUTOPILOTS = ("px4", "ardupilot")


@dataclass(frozen=True)
class AxisCalibration:
    """One calibration's cubic (in its recording's unit), for one axis of one sensor kind."""

    folder: Path
    sensor: str
    unit: str
    axis: str
    poly: Any  # OffsetPolynomial
    px4_device_id: int | None
    static_level: float | None = None  # the median offset (calibration.json's export.static_level)
    device: dict[str, Any] | None = None  # the methods a device runs (calibration.json's device)
    held_out: dict[str, Any] | None = None  # best, drift per method (calibration.json's ranking)
    left_out: dict[str, str] = field(default_factory=dict)  # fitted methods no device runs, and why

    def c_name(self, method: str) -> str:
        """The C name of ``method``'s export: ``tc_gyro_x_poly3``."""
        return f"tc_{self.sensor}_{self.axis}_{method}"

    def cubic_line(self) -> str | None:
        """``gyro x: the cubic the autopilots run leaves 0.106 deg/s held out; model 0.054 (the best)``
        when the best held-out method is not the cubic, else None."""
        ranked = self.held_out or {}
        best = ranked.get("best")
        if not ranked.get("held_out") or best in (None, "poly3"):
            return None
        drift = ranked.get("drift", {})
        cubic = (f"leaves {drift['poly3']:.3g} {self.unit} held out" if drift.get("poly3") is not None
                 else "was not scored (calibrate with poly3 among methods=)")
        return (f"{self.sensor} {self.axis}: the cubic the autopilots run {cubic}; the best held-out method, {best}, "
                f"{drift.get(best, float('nan')):.3g}")


def read_calibration(folder: str | Path) -> AxisCalibration:
    """The exportable cubic of a ``tcbench calibrate`` output folder; one line when it has none."""
    from tcbench.compensation.px4 import OffsetPolynomial

    path = Path(folder) / "calibration.json"
    if not path.is_file():
        raise CommandError(f"calibrations: {folder}: no calibration.json (a tcbench calibrate out= folder)")
    try:
        about = json.loads(path.read_text())
        fit = about["export"]
        poly = OffsetPolynomial(tuple(float(c) for c in fit["x"]), float(fit["tref_c"]),  # type: ignore[arg-type]
                                float(fit["tmin_c"]), float(fit["tmax_c"]))
        sensor, unit, axis = about["sensor"], about["unit"], about.get("axis")
        level = fit.get("static_level")
        static_level = float(level) if level is not None else None
        device = dict(about.get("device") or {})
        left_out = device.pop("_left_out", {})
        held_out = {k: about[k] for k in ("held_out", "best", "drift") if k in about}
    except (ValueError, KeyError, TypeError) as exc:
        raise CommandError(f"calibrations: {path}: not a calibration tcbench export reads ({exc})") from None
    if axis not in ("x", "y", "z"):
        raise CommandError(f"calibrations: {folder}: the recording's axis is unknown; import it with axes=x|y|z, "
                           "or calibrate it again with axis=x|y|z")
    px4_id = about.get("px4_device_id")
    return AxisCalibration(Path(folder), str(sensor), str(unit), str(axis), poly,
                           int(px4_id) if px4_id is not None else None, static_level,
                           device or None, held_out, left_out)


@dataclass(frozen=True)
class RunNetwork:
    """The network a ``tcbench run`` compensation job kept (its ``device.json``)."""

    source: str  # the run id, or the device.json given
    name: str  # the C name's stem: tc_<sensor>_<learner>_<run id's first 8>
    about: str  # the header's line
    spec: dict[str, Any]


def read_run(given: str) -> list[RunNetwork]:
    """The networks of one ``runs=`` entry: a run id in the store ``$MLFLOW_TRACKING_URI`` (else
    ./mlflow.db), or the path of a run's ``device.json``; one line when it has none a device runs."""
    from tcbench.compensation.run_device import FILE

    path = Path(given)
    if path.is_file():
        run_id = path.parent.parent.name if path.parent.name == "artifacts" else path.parent.name
    else:
        from tcbench.tracking.store import StoreError, check_store, client, local_artifact_dir

        try:
            uri = check_store(None, create=False)
            run = client(uri).get_run(given)
        except StoreError as exc:
            raise CommandError(f"runs: {exc}") from None
        except Exception:  # MLflow's lookup of an unknown id raises its own exception types
            raise CommandError(f"runs: {given}: no such run in {uri} (a tcbench run's id, or the path of its "
                               f"{FILE})") from None
        folder = local_artifact_dir(run.info.artifact_uri)
        path = (folder / FILE) if folder is not None else Path(given) / FILE
        if not path.is_file():
            raise CommandError(f"runs: {given}: the run kept no {FILE} (not a compensation run of a fitted model, "
                               "or run before tcbench kept one)")
        run_id = given
    try:
        about = json.loads(path.read_text())
        device, left = dict(about["device"]), dict(about.get("left_out") or {})
        sensor, unit = str(about.get("sensor") or "sensor"), str(about.get("unit") or "")
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CommandError(f"runs: {path}: not a {FILE} tcbench export reads ({exc})") from None
    if not device:
        why = "; ".join(f"{k}: {v}" for k, v in left.items()) or "no network"
        raise CommandError(f"runs: {given}: no model a device runs ({why})")
    return [RunNetwork(given, f"tc_{sensor}_{method}_{run_id[:8]}",
                       f"{sensor}, output in {unit}: the {about.get('method', method)} "
                       f"{'network' if 'hidden' in spec else 'model'} of tcbench run {run_id} "
                       f"on {about.get('task', '?')}", spec) for method, spec in device.items()]


def check_runs(cfg: ExportConfig) -> list[RunNetwork]:
    """The networks of ``runs=``; one line when a format other than C is asked of them."""
    if not cfg.runs:
        return []
    if other := [f for f in cfg.formats if f != "c"]:
        raise CommandError(f"runs: a run's network is written as C only (formats=[c]), not {', '.join(other)}")
    return [n for given in cfg.runs for n in read_run(str(given))]


def check_export(cfg: ExportConfig) -> dict[str, dict[str, AxisCalibration]]:
    """Every argument before any work; the calibrations by sensor kind and axis."""
    from tcbench.compensation.px4 import px4_covers

    if not cfg.calibrations and not cfg.runs:
        raise CommandError("calibrations=[DIR,...] is required: the out= folders of tcbench calibrate "
                           "(or runs=[ID,...]: tcbench run compensation runs, formats=[c])")
    if bad := [f for f in cfg.formats if f not in FORMATS]:
        raise CommandError(f"formats: {unknown_name('format', bad[0], FORMATS)}")
    if not cfg.formats:
        raise CommandError(f"formats: give at least one of {', '.join(FORMATS)}")
    if not 0 <= cfg.px4_instance <= 3:
        raise CommandError(f"px4_instance must be 0..3, got {cfg.px4_instance}")
    if not 1 <= cfg.ardupilot_imu <= 3:
        raise CommandError(f"ardupilot_imu must be 1..3, got {cfg.ardupilot_imu}")
    writable_folder(cfg.out)
    autopilots = [f for f in dict.fromkeys(cfg.formats) if f in AUTOPILOTS]
    by_sensor: dict[str, dict[str, AxisCalibration]] = {}
    for folder in cfg.calibrations:
        cal = read_calibration(folder)
        if "c" in cfg.formats and not cal.device:
            raise CommandError(f"calibrations: {folder}: its calibration.json holds no method a device runs "
                               "(calibrated before tcbench wrote them, or with none of "
                               "poly3, poly3_rate, bp, bp_gd, elman); calibrate it again for formats=[c]")
        if autopilots and not px4_covers(cal.sensor):
            raise CommandError(f"calibrations: {folder}: a {cal.sensor} recording; the autopilots calibrate gyro and accel")
        axes = by_sensor.setdefault(cal.sensor, {})
        if cal.axis in axes:
            raise CommandError(f"calibrations: {axes[cal.axis].folder} and {folder} are both {cal.sensor} axis {cal.axis}")
        axes[cal.axis] = cal
    names = [n.name for n in check_runs(cfg)]
    if twice := sorted({n for n in names if names.count(n) > 1}):
        raise CommandError(f"runs: {twice[0]} is given twice")
    free_outputs(cfg.out, [FILES[f] for f in autopilots] + c_files(by_sensor) * ("c" in cfg.formats)
                 + [f"{n}.{ext}" for n in names for ext in ("h", "c")], cfg.overwrite)
    if "px4" in cfg.formats:
        for sensor in by_sensor:
            device_id(cfg, sensor, by_sensor[sensor])
            static_levels(sensor, by_sensor[sensor])
    return by_sensor


def c_files(by_sensor: dict[str, dict[str, AxisCalibration]]) -> list[str]:
    """The C files ``formats=[c]`` writes into OUT/: a header and a source per method and axis."""
    return [f"{cal.c_name(m)}.{ext}" for axes in by_sensor.values() for cal in axes.values()
            for m in cal.device or {} for ext in ("h", "c")]


def write_c_files(by_sensor: dict[str, dict[str, AxisCalibration]], folder: Path) -> list[Path]:
    """Every calibration's device methods as C in ``folder``."""
    from tcbench.compensation.c_export import write_c

    written: list[Path] = []
    for axes in by_sensor.values():
        for cal in axes.values():
            for method, spec in (cal.device or {}).items():
                about = (f"{cal.sensor} axis {cal.axis}, output in {cal.unit}: tcbench calibrate's {method} of "
                         f"{cal.folder.name}")
                try:
                    written += write_c(spec, cal.c_name(method), folder, about)
                except (KeyError, TypeError, ValueError) as exc:
                    raise CommandError(f"calibrations: {cal.folder}: its device method {method} cannot be "
                                       f"written as C ({exc}); calibrate it again") from None
    return written


def write_run_c_files(networks: list[RunNetwork], folder: Path) -> list[Path]:
    """Every run network as C in ``folder``."""
    from tcbench.compensation.c_export import write_c

    written: list[Path] = []
    for n in networks:
        try:
            written += write_c(n.spec, n.name, folder, n.about)
        except (KeyError, TypeError, ValueError) as exc:
            raise CommandError(f"runs: {n.source}: its network cannot be written as C ({exc})") from None
    return written


def static_levels(sensor: str, axes: dict[str, AxisCalibration]) -> dict[str, float]:
    """Each axis's static level when PX4 leaves it to the ordinary calibration (an accelerometer,
    :func:`~tcbench.compensation.px4.keeps_static_level`), else none; one line for a calibration
    written without it."""
    from tcbench.compensation.px4 import keeps_static_level

    if not keeps_static_level(sensor):
        return {}
    if without := [c.folder for c in axes.values() if c.static_level is None]:
        raise CommandError(f"calibrations: {without[0]}: no static level in its calibration.json, which PX4's {sensor} "
                           "polynomial leaves out; calibrate it again, or formats=[ardupilot]")
    return {a: float(c.static_level) for a, c in axes.items()}  # type: ignore[arg-type]


def device_id(cfg: ExportConfig, sensor: str, axes: dict[str, AxisCalibration]) -> int:
    """PX4's ``TC_*_ID`` of ``sensor``: ``device_id=`` (a number, or per kind), else the one id the
    log gave every axis; one line when neither says."""
    given = cfg.device_id.get(sensor) if isinstance(cfg.device_id, dict) else cfg.device_id
    if given is not None:
        try:
            return int(given)
        except (TypeError, ValueError):
            raise CommandError(f"device_id: {given!r} is not an integer (PX4's device id, e.g. 2293768)") from None
    logged = {c.px4_device_id for c in axes.values()}
    if len(logged) == 1 and None not in logged:
        return int(logged.pop())  # type: ignore[arg-type]
    kind = kinds.get(sensor)
    raise CommandError(f"device_id=: PX4 applies TC_{kind.px4_letter}{cfg.px4_instance}_* only to "
                       f"the {sensor} whose device id it names; give it (its CAL_{kind.px4_cal}n_ID "
                       "parameter, or the log's), or formats=[ardupilot]")


def cubic_comments(by_sensor: dict[str, dict[str, AxisCalibration]]) -> tuple[list[str], list[str]]:
    """The lines saying what the autopilots' cubic leaves where the best held-out method is not the
    cubic, and the comments the parameter files carry (those lines, and which methods C can run)."""
    from tcbench.compensation.c_export import EXPORTED

    notes = [ln for axes in by_sensor.values() for c in axes.values() if (ln := c.cubic_line())]
    bests = {(c.held_out or {}).get("best") for axes in by_sensor.values() for c in axes.values() if c.cubic_line()}
    comments = [f"tcbench: these are the cubic's coefficients; {ln}" for ln in notes]
    if exportable := sorted(bests & set(EXPORTED)):
        comments.append(f"tcbench export formats=[c] writes {', '.join(exportable)} as C for a sensor's own processor")
    return notes, comments


def export(cfg: ExportConfig) -> dict[str, Path]:
    """Write the parameter files; print what each holds."""
    from tcbench.compensation.ardupilot import ardupilot_parameters, write_parm
    from tcbench.compensation.px4 import common_range, px4_factor, px4_parameters, px4_polynomial, write_parameters

    by_sensor = check_export(cfg)
    networks = check_runs(cfg)
    autopilots = any(f in AUTOPILOTS for f in cfg.formats)
    to_si = {s: px4_factor(s, next(iter(axes.values())).unit) for s, axes in by_sensor.items()} if autopilots else {}
    polys = {s: {a: c.poly for a, c in axes.items()} for s, axes in by_sensor.items()}
    for sensor, axes in polys.items() if autopilots else ():
        missing = [a for a in ("x", "y", "z") if a not in axes]
        if missing:
            print(f"tcbench: {sensor} axis {', '.join(missing)}: no calibration given; its coefficients are 0 "
                  "(no correction)")
        try:
            shared = common_range(axes)
        except ValueError as exc:
            raise CommandError(f"calibrations: {sensor}: {exc}") from None
        if shared != axes:
            first = next(iter(shared.values()))
            print(f"tcbench: {sensor}: the axes were fitted over different temperatures; all held to "
                  f"{first.tmin_c:.2f}..{first.tmax_c:.2f} degC, where every axis was fitted")
    out = Path(cfg.out)
    replaced: list[Path] = []
    with writing_errors(out, "the parameter files"), staged_dir(out, [], cfg.overwrite, replaced) as tmp:
        written: dict[str, Path] = {}
        notes, comments = cubic_comments(by_sensor)
        if "px4" in cfg.formats:
            params: dict[str, float | int] = {}
            for sensor, axes in polys.items():
                levels = static_levels(sensor, by_sensor[sensor])
                px4_axes = {a: px4_polynomial(p, sensor, levels.get(a, 0.0)) for a, p in axes.items()}
                params |= px4_parameters(px4_axes, sensor, cfg.px4_instance,
                                         device_id(cfg, sensor, by_sensor[sensor]), to_px4_unit=to_si[sensor])
            written["px4"] = write_parameters(params, tmp / FILES["px4"], list(polys), comments)
        if "ardupilot" in cfg.formats:
            try:
                ap = ardupilot_parameters(polys, cfg.ardupilot_imu, to_si)
            except ValueError as exc:
                raise CommandError(f"ardupilot: {exc}") from None
            written["ardupilot"] = write_parm(ap, tmp / FILES["ardupilot"], comments)
        if "c" in cfg.formats:
            written |= {f"c {p.name}": p for p in write_c_files(by_sensor, tmp)}
            written |= {f"c {p.name}": p for p in write_run_c_files(networks, tmp)}
    written = moved(written, tmp, out)
    say_replaced(replaced)
    if any(f in written for f in AUTOPILOTS):
        for line in notes:
            print(f"tcbench: {line}")
    if "c" in cfg.formats:
        sources = [p for k, p in written.items() if k.startswith("c ") and p.suffix == ".c"]
        print(f"tcbench: wrote {len(sources)} C99 compensator{'s' * (len(sources) != 1)} into {out} ({', '.join(p.stem for p in sources)}: "
              "a .h and a .c each; init once, update per sample; -DTC_..._FLOAT for the float build)")
        from tcbench.compensation.c_export import EXPORTED, NOT_EXPORTED

        again = "its parameters are not in calibration.json: calibrate again"
        left = {f"{c.sensor} {c.axis} {m}": c.left_out.get(m, again if m in EXPORTED else NOT_EXPORTED.get(m, m))
                for axes in by_sensor.values() for c in axes.values()
                for m in (c.held_out or {}).get("drift", {}) if m not in (c.device or {})}
        if left:
            print("tcbench: not written as C: " + "; ".join(f"{k} ({why})" for k, why in sorted(left.items())))
    every = ", ".join(f"{s} {''.join(sorted(a))}" for s, a in polys.items())
    if "px4" in written:
        print(f"tcbench: wrote {written['px4']} (PX4 TC_* of {every}, instance {cfg.px4_instance}; "
              "paste into the NuttX console or run from the SD card)")
        for sensor in polys:
            if levels := static_levels(sensor, by_sensor[sensor]):
                each = ", ".join(f"{a} {v:.6g}" for a, v in sorted(levels.items()))
                print(f"  {sensor}: TC_{kinds.get(sensor).px4_letter}{cfg.px4_instance}_X0_* leave out the static level "
                      f"({each} {next(iter(by_sensor[sensor].values())).unit}, gravity included), as PX4 fits it: "
                      f"the ordinary calibration CAL_{kinds.get(sensor).px4_cal}n_* keeps it")
    if "ardupilot" in written:
        print(f"tcbench: wrote {written['ardupilot']} (ArduPilot INS_TCAL{cfg.ardupilot_imu}_* of {every}; "
              "load it in the ground station)")
    return written


# tcbench export runs in the command line's process (CommandSpec.runs_here): its check and its work
def check(cfg: ExportConfig) -> None:
    """Every argument of an export, before any export of a sweep is written."""
    check_export(cfg)


def work(cfg: ExportConfig) -> int:
    """Write the parameter files of ``cfg``; exit code 0."""
    export(cfg)
    return 0
