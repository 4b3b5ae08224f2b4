"""The statistics of a diagnosis in one object: :class:`DiagnoseSettings`.

Every number that sets how a diagnosis decides (thresholds, false-alarm levels, the sizes of the
cross-validation and of the tests, what the screens and detectors search) is a field of one small
frozen section, with its unit in its name where it has one and the reason for its value in its
``metadata["doc"]``. The defaults are the calibrated values (``experiments/diagnose-*``);
``conf/diagnose.yaml``'s ``settings:`` block mirrors them key for key, and ``tcbench diagnose
settings.<section>.<field>=`` changes one. The pipeline passes each stage its section
(:func:`tcbench.diagnose.diagnosis.diagnose`); a public function's default is the section of
:data:`DEFAULTS`.

What stays a module constant is not a statistic: identities (``MAD_TO_SIGMA``, the flicker floor
of the Allan deviation), measured properties of an estimator, the numerics of an algorithm (chunk
sizes, ridge floors, grids of a filter clock), the report's format (how many values are listed,
plot sizes) and the terms' own search grids (each term class declares its parameter's grid, as a
plug-in term does).

This module imports nothing but the standard library: ``tcbench diagnose --help`` lists the
settings from it without importing the diagnosis.
"""

from __future__ import annotations

import dataclasses
import textwrap
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from tcbench.errors import did_you_mean

__all__ = ["DEFAULTS", "DetectorSettings", "DiagnoseSettings", "SettingsError", "differing", "documented",
           "from_mapping", "meanings", "report_mapping", "to_mapping", "yaml_lines"]


class SettingsError(ValueError):
    """A setting that is not one, or a value it cannot take; the message names the key."""


@dataclass(frozen=True)
class Check:
    """What a setting's value must be: ``ok(value)`` and the words for it."""

    ok: Callable[[Any], bool]
    says: str


POSITIVE = Check(lambda v: v > 0, "a number > 0")
NONNEGATIVE = Check(lambda v: v >= 0, "a number >= 0")
PROBABILITY = Check(lambda v: 0 < v < 1, "a probability in (0, 1)")
SHARE = Check(lambda v: 0 < v <= 1, "a share in (0, 1]")
FACTOR = Check(lambda v: v >= 1, "a factor >= 1")
COUNT = Check(lambda v: v >= 1, "a whole number >= 1")
TWO = Check(lambda v: v >= 2, "a whole number >= 2")
FOUR = Check(lambda v: v >= 4, "a whole number >= 4")
ODD = Check(lambda v: v >= 3 and v % 2 == 1, "an odd whole number >= 3")
SEED = Check(lambda v: v >= 0, "a seed >= 0")


def setting(default: Any, doc: str, check: Check = POSITIVE) -> Any:
    """A field of a settings section: its default, the one-line reason for it and its check."""
    return field(default=default, metadata={"doc": doc, "check": check})


def section(cls: type, doc: str) -> Any:
    """A field holding a section (its defaults), with what the section sets."""
    return field(default_factory=cls, metadata={"doc": doc})


@dataclass(frozen=True)
class SelectionSettings:
    """The forward selection: the held-out gain and the significance a term needs."""

    detection_threshold_sigma2: float = setting(
        10.0, "penalised held-out gain a library effect must exceed; "
              "calibrated on controls (experiments/diagnose-concealed/calibrate.py)")
    open_threshold_sigma2: float = setting(
        25.0, "the same for an open-world term, higher because its detectors search positions and periods; "
              "also the gain the default thermometer window must pay")
    open_threshold_max_factor: float = setting(
        4.0, "the open-world threshold grows with the squared ratio of the noisiest level to the RMS, "
             "at most this factor", FACTOR)
    penalty_sigma2_per_param: float = setting(
        2.0, "Akaike's penalty per added parameter, subtracted from the held-out gain", NONNEGATIVE)
    wald_threshold: float = setting(
        25.0, "cluster-robust Wald statistic a kept effect must exceed; calibrated with the gain threshold")
    wald_lags: int = setting(
        4, "neighbouring Wald clusters whose score covariances enter the robust variance (Bartlett weights): "
           "noise correlated over up to this many clusters (an hour at 900 s) is not taken for an effect", COUNT)
    most_of_excess: float = setting(
        0.5, "an effect removing this share of the held-out error above the noise is tried by the surrogate "
             "test when the Wald test rejects it", SHARE)
    max_effects: int = setting(6, "most effects the forward selection adds to the starting model", COUNT)


@dataclass(frozen=True)
class PlanSettings:
    """The cross-validation blocks and the robust test's clusters, sized to the record
    (:mod:`tcbench.diagnose.select.plan`)."""

    folds: int = setting(5, "cross-validation folds (interleaved blocks)", TWO)
    block_windows: float = setting(
        2.0, "a CV block spans at least this many thermometer-smoothing windows, so a held-out block is not "
             "predicted by its neighbours' smoothed thermometer")
    max_block_s: float = setting(900.0, "longest CV block and cluster: the length the library proof was "
                                        "calibrated with on 8-12 h records")
    blocks_per_record: int = setting(24, "CV blocks the record is cut into, within the block bounds (at least four per fold)", COUNT)
    cluster_windows: float = setting(2.5, "a Wald cluster spans at least this many thermometer-smoothing windows")
    clusters_per_record: int = setting(32, "Wald clusters the record is cut into, within the cluster bounds", COUNT)
    min_clusters: int = setting(
        24, "fewer clusters than this cannot estimate the variance of slow noise: the surrogate test decides",
        COUNT)


@dataclass(frozen=True)
class SurrogateSettings:
    """The spectral surrogate test (:mod:`tcbench.diagnose.select.surrogate`)."""

    draws: int = setting(199, "surrogates drawn at most (the draws stop once the p-value exceeds the level)",
                         COUNT)
    level: float = setting(0.005, "p-value at or below which an effect is kept: no surrogate of 199 reaches it",
                           PROBABILITY)
    seed: int = setting(20240611, "the surrogates' generator: same recording, same diagnosis", SEED)


@dataclass(frozen=True)
class ReferenceSettings:
    """The physics-agnostic reference fit (:mod:`tcbench.diagnose.select.reference`)."""

    structure_ratio: float = setting(
        1.25, "final / reference held-out RMSE above which deterministic structure remains (flicker not judged)")
    n_lags: int = setting(6, "first-order lags of the thermometer in the reference, log-spaced", COUNT)
    max_lag_share: float = setting(0.25, "the longest lag's time constant as a share of the record", SHARE)


@dataclass(frozen=True)
class SmoothingSettings:
    """The thermometer smoothing (:mod:`tcbench.diagnose.signals`)."""

    default_window_s: float = setting(
        120.0, "smoothing window of a record without a coarse staircase; a shorter fitted one must beat it")
    bias_to_noise: float = setting(
        0.5, "the fitted window halves while the smoothing's RMS bias exceeds this share of its noise")


@dataclass(frozen=True)
class DataSettings:
    """What a record must hold to be diagnosed at all (:func:`tcbench.diagnose.signals.prepare`)."""

    min_span_c: float = setting(2.0, "least temperature span: a model cannot be identified at constant "
                                     "temperature")
    min_samples: int = setting(200, "fewest samples a diagnosis takes", COUNT)


@dataclass(frozen=True)
class LocateSettings:
    """Where a residual departs from white noise: the ``mismatch`` scan (:mod:`tcbench.diagnose.select.locate`)."""

    false_alarm: float = setting(0.01, "family-wise false-alarm probability of the scan on white noise",
                                 PROBABILITY)
    min_samples: int = setting(100, "fewest samples the scan takes", COUNT)
    window_s: float = setting(180.0, "window of the time scan")
    band_c: float = setting(5.0, "temperature bin of the band scan and the two-group tests")
    still_rate_c_per_min: float = setting(0.05, "|dT/dt| that separates soak from ramp")
    rate_window_s: float = setting(60.0, "span over which dT/dt is taken")
    min_windows: int = setting(10, "the time scan shrinks its windows to have at least this many", COUNT)
    max_windows: int = setting(1500, "... and widens them to have at most this many (memory of the K x K scan)",
                               COUNT)
    min_group_samples: int = setting(10, "a temperature bin enters a two-group test with this many per group",
                                     COUNT)
    min_allan_samples: int = setting(10, "shortest Allan tau; the longest is a tenth of the record",
                                     COUNT)
    max_findings: int = setting(20, "most regions reported per scan family", COUNT)


@dataclass(frozen=True)
class DetectorSettings:
    """The detectors that propose open-world terms (:mod:`tcbench.diagnose.terms.detectors`)."""

    max_bins: int = setting(3000, "most time bins of the residual the change-point search reads", COUNT)
    line_bins: int = setting(1200, "most time bins of the periodogram (periods down to three bins)", COUNT)
    min_bin_s: float = setting(10.0, "narrowest time bin")
    duty_phases: int = setting(64, "phase bins a switched load's cycle is folded into", TWO)
    n_changes: int = setting(3, "change points proposed per round", COUNT)
    n_lines: int = setting(3, "periodogram peaks proposed per round", COUNT)
    n_bumps: int = setting(3, "temperature bumps proposed per round", COUNT)
    gap_factor: float = setting(5.0, "a gap longer than this many median sample spacings may hide a restart")
    max_gaps: int = setting(12, "longest gaps proposed as restarts", COUNT)
    bump_widths_c: tuple[float, ...] = setting((1.0, 1.5, 2.5, 4.0, 6.0), "widths of the Gaussian bumps "
                                                                         "matched against the residual")
    bump_spans: float = setting(4.0, "a bump of width w is searched where the temperature spans this many w")
    min_step_bins: int = setting(8, "binned residual means the change-point search needs", TWO)
    min_line_bins: int = setting(16, "binned residual means the periodogram needs", FOUR)
    line_cycles: float = setting(1.5, "the longest period searched fits this many times in the span")
    temp_bin_c: float = setting(0.1, "temperature bin of the bump search")


@dataclass(frozen=True)
class OutlierSettings:
    """Isolated outliers (:mod:`tcbench.diagnose.screens.outliers`)."""

    alpha: float = setting(0.01, "family-wise false-alarm probability over the whole record", PROBABILITY)
    min_z: float = setting(4.5, "the bound never drops below this many robust sigmas (short records)")
    tail: float = setting(1.1, "a sample minus its neighbours' median has heavier tails than its MAD implies",
                          FACTOR)
    window_samples: int = setting(31, "samples in the running median that sets the local level", ODD)
    max_run_samples: int = setting(5, "longest run of flagged samples still called a spike", COUNT)
    min_scale_sigma: float = setting(0.5, "a robust scale below this many white sigmas is a coarse grid's, "
                                          "not the noise's")


@dataclass(frozen=True)
class SaturationSettings:
    """Clipping at a ceiling or a floor (:mod:`tcbench.diagnose.screens.saturation`)."""

    alpha: float = setting(0.01, "family-wise false-alarm probability over the two sides", PROBABILITY)
    density_ratio: float = setting(3.0, "density at the extreme over the next cell's that an unclipped output "
                                        "can reach")
    min_count: int = setting(5, "fewest samples at the clip level", COUNT)
    tol_sigma: float = setting(1e-3, "tolerance of the clip level for a continuous output")
    next_sigma: float = setting(0.25, "width of the cell next to the clip level")
    episode_gap_samples: int = setting(30, "clipped samples closer than this belong to one episode", COUNT)
    max_episode_share: float = setting(0.5, "episodes wider than this share of the record: only the clipped "
                                            "samples get zero weight", SHARE)
    clear_sigma: float = setting(3.0, "white sigmas between a fitted value and a clip level for the variance "
                                      "test to use the sample")


@dataclass(frozen=True)
class QuantisationSettings:
    """The output (and thermometer) read on a grid (:mod:`tcbench.diagnose.screens.quantisation`)."""

    tolerance_steps: float = setting(0.02, "how far a jump may sit from an integer multiple of the step",
                                     PROBABILITY)
    min_fraction: float = setting(0.99, "share of the non-zero jumps that must be multiples of the step", SHARE)
    min_resultant: float = setting(0.99, "phase alignment of the values on the lattice (mean resultant length)",
                                   SHARE)
    min_jumps: int = setting(20, "non-zero jumps needed to judge a lattice", COUNT)
    min_step_sigma: float = setting(0.05, "an output lattice finer than this many white sigmas is not reported")
    clip_sigma: float = setting(8.0, "on a lattice, differences clipped at this many sigmas (or steps) for the "
                                     "white sigma")


@dataclass(frozen=True)
class ThermometerSettings:
    """The thermometer's staircase and the smoothing it needs (:func:`~tcbench.diagnose.screens.quantisation.thermometer_steps`)."""

    min_step_c: float = setting(0.05, "a thermometer lattice finer than this is not reported")
    dither_spread_steps: float = setting(0.36, "reading spread about its smoothed value above which it "
                                               "is dithered")
    periods: float = setting(3.0, "staircase periods the widened smoothing window spans")
    rate_window_s: float = setting(1800.0, "window of the local line that gives the typical ramp rate")
    max_window_share: float = setting(
        0.25, "the rate window and the widened smoothing window are at most this share of the record, so a "
              "short record is not rated or smoothed over most of its length", SHARE)
    fast_quantile: float = setting(0.9, "quantile of |rate| that stands for the fast ramps (a quantile, not the "
                                        "largest: one fast corner does not set it)", PROBABILITY)
    moving_share: float = setting(0.2, "a sample is on a ramp when its |rate| is above this share of the "
                                       "fast_quantile of |rate|", SHARE)


@dataclass(frozen=True)
class VarianceSettings:
    """Noise whose level changes with temperature or time (:mod:`tcbench.diagnose.screens.variance`)."""

    alpha: float = setting(0.01, "family-wise false-alarm probability over the temperature and the time test",
                           PROBABILITY)
    min_pairs: int = setting(16, "pairs of consecutive samples per block at least", COUNT)
    max_blocks: int = setting(400, "most blocks", COUNT)
    min_blocks: int = setting(12, "fewer blocks and the record is not tested", FOUR)
    clip_sigma: float = setting(8.0, "robust sigmas at which a pair difference is clipped")
    bins: int = setting(8, "bins of equal count along temperature (time) that place the noisiest band", TWO)
    min_sigma_ratio: float = setting(1.2, "noisiest over quietest bin's sigma below which a change is not "
                                          "reported", FACTOR)


@dataclass(frozen=True)
class FlickerSettings:
    """Flicker (``bias_instability``): the Allan test of the final residual, whose flicker the
    kept effects are then rechecked against (:mod:`tcbench.diagnose.screens.flicker`; the recheck
    takes the exact variance of their scores under it, no draws)."""

    false_alarm: float = setting(0.01, "false-alarm probability of the Allan test over its taus", PROBABILITY)


@dataclass(frozen=True)
class ScreenSettings:
    """The screens: the tests whose structure is not a term of the mean model."""

    outliers: OutlierSettings = section(OutlierSettings, "isolated outliers")
    saturation: SaturationSettings = section(SaturationSettings, "clipping")
    quantisation: QuantisationSettings = section(QuantisationSettings, "the output's grid")
    thermometer: ThermometerSettings = section(ThermometerSettings, "the thermometer's staircase")
    variance: VarianceSettings = section(VarianceSettings, "a changing noise level")
    flicker: FlickerSettings = section(FlickerSettings, "flicker")


@dataclass(frozen=True)
class ShortSettings:
    """The tests of a record too short for a full diagnosis (:mod:`tcbench.diagnose.short.short_record`)."""

    alpha: float = setting(0.01, "level of every short-record test; intervals are 1 - alpha", PROBABILITY)
    min_fit_samples: int = setting(30, "a slope and its noise's autocorrelation need this many samples", COUNT)
    min_side_samples: int = setting(15, "a level step is searched this many samples (at least) from either end",
                                    COUNT)
    side_share: float = setting(0.05, "... and this share of the record: a step at the edge is the edge's noise",
                                PROBABILITY)
    min_slope_span_c: float = setting(0.5, "a temperature slope needs the smoothed thermometer to move this much")
    ramp_share: float = setting(0.5, "a ramp starts where |dT/dt| rises through this share of its largest value",
                                SHARE)
    one_way_corr: float = setting(0.9, "|corr(time, temperature)| above which a slope is also a drift in time",
                                  SHARE)
    seed: int = setting(0, "the surrogates' generator: a report is repeatable", SEED)


@dataclass(frozen=True)
class RateSettings:
    """A record of more rows than a diagnosis takes in time and memory: its thermal terms fitted on
    bin means, its noise terms measured on every sample (:mod:`tcbench.diagnose.rate.native_rate`). Not a
    statistic of the tests: it decides which record they are given, so report.json's
    ``statistics.settings`` leaves it out and the report's ``native_rate`` says what it did."""

    max_rows: int = setting(
        100_000, "a record of more rows is diagnosed on bin means (25-50 s of one core and 550 MB at this many "
                 "rows, tcbench/diagnose/rate/cost.py, where 2.7 M rows would take 10-20 min and 8 GB)", COUNT)
    max_bin_s: float = setting(
        1.0, "the bin of a record averaged: the 1 s clock of the lag filter, a twentieth of the shortest thermal lag "
             "searched (20 s) and a tenth of the detectors' narrowest bin (10 s)")


FRONT_STAGE = ("rate",)  # sections that choose the record the diagnosis is given, not how it tests


@dataclass(frozen=True)
class DiagnoseSettings:
    """Every statistic of a diagnosis, by section (see the module doc); checked when made."""

    selection: SelectionSettings = section(SelectionSettings, "the forward selection: gains and significance")
    plan: PlanSettings = section(PlanSettings, "cross-validation blocks and Wald clusters sized to the record")
    surrogate: SurrogateSettings = section(SurrogateSettings, "the spectral surrogate test")
    reference: ReferenceSettings = section(ReferenceSettings, "the physics-agnostic reference fit")
    smoothing: SmoothingSettings = section(SmoothingSettings, "the thermometer smoothing")
    data: DataSettings = section(DataSettings, "what a record must hold")
    locate: LocateSettings = section(LocateSettings, "where a residual departs from white noise")
    detectors: DetectorSettings = section(DetectorSettings, "the detectors of the open-world terms")
    screens: ScreenSettings = section(ScreenSettings, "the screens")
    short: ShortSettings = section(ShortSettings, "the tests of a record too short for a full diagnosis")
    rate: RateSettings = section(RateSettings, "a record longer than a diagnosis takes: bin means for the thermal "
                                               "terms, every sample for the noise")

    def __post_init__(self) -> None:
        check(self)


def _walk(obj: Any, prefix: str) -> list[tuple[str, dataclasses.Field[Any], Any]]:
    """``(dotted key, field, value)`` of every leaf setting of ``obj``."""
    out: list[tuple[str, dataclasses.Field[Any], Any]] = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if dataclasses.is_dataclass(value):
            out += _walk(value, f"{prefix}{f.name}.")
        else:
            out.append((f"{prefix}{f.name}", f, value))
    return out


def check(settings: Any, prefix: str = "settings.") -> None:
    """:class:`SettingsError` naming the first setting of ``settings`` whose value its check refuses."""
    for key, f, value in _walk(settings, prefix):
        rule: Check = f.metadata["check"]
        values = value if isinstance(value, tuple) else (value,)
        if isinstance(value, tuple) and not value:
            raise SettingsError(f"{key}: give at least one value")
        for v in values:
            if not rule.ok(v):
                raise SettingsError(f"{key}: must be {rule.says}, got {value!r}")


def _typed(key: str, kind: Any, value: Any) -> Any:
    """``value`` as the setting's type (``int``, ``float`` or a tuple of floats); SettingsError otherwise."""
    def number(v: Any, want: type) -> Any:
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise SettingsError(f"{key}: must be {'a whole number' if want is int else 'a number'}, got {value!r}")
        if want is int:
            if not float(v).is_integer():
                raise SettingsError(f"{key}: must be a whole number, got {value!r}")
            return int(v)
        return float(v)

    if typing.get_origin(kind) is tuple:
        if isinstance(value, str) or not isinstance(value, list | tuple):
            raise SettingsError(f"{key}: must be a list of numbers, got {value!r}")
        return tuple(number(v, float) for v in value)
    return number(value, kind)


def from_mapping(given: Mapping[str, Any] | None, cls: type | None = None, prefix: str = "settings.") -> Any:
    """The settings ``given`` as a mapping (``{section: {field: value}}``, e.g. ``conf/diagnose.yaml``'s
    ``settings:``), missing ones at their defaults; :class:`SettingsError` naming the key of an
    unknown setting, a value of the wrong type or one its check refuses."""
    cls = DiagnoseSettings if cls is None else cls
    given = dict(given or {})
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    if unknown := [k for k in given if k not in names]:
        meant = did_you_mean(unknown[0], names)
        raise SettingsError(f"{prefix}{unknown[0]}: no such setting (known: {', '.join(names)})"
                            + (f"; did you mean {prefix + meant!r}?" if meant else ""))
    values: dict[str, Any] = {}
    for name, value in given.items():
        kind = hints[name]
        if dataclasses.is_dataclass(kind):
            if not isinstance(value, Mapping):
                raise SettingsError(f"{prefix}{name}: a section, give its keys ({prefix}{name}.KEY=VALUE)")
            values[name] = from_mapping(value, kind, f"{prefix}{name}.")
        else:
            values[name] = _typed(f"{prefix}{name}", kind, value)
    made = cls(**values)
    if cls is not DiagnoseSettings:
        check(made, prefix)
    return made


def to_mapping(settings: Any) -> dict[str, Any]:
    """``settings`` as plain nested data (tuples as lists): report.json's, YAML's."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(settings):
        value = getattr(settings, f.name)
        out[f.name] = (to_mapping(value) if dataclasses.is_dataclass(value)
                       else list(value) if isinstance(value, tuple) else value)
    return out


def report_mapping(settings: Any) -> dict[str, Any]:
    """report.json's ``statistics.settings``: :func:`to_mapping` without the :data:`FRONT_STAGE`
    sections (the report's ``native_rate`` records them where they changed the record)."""
    return {k: v for k, v in to_mapping(settings).items() if k not in FRONT_STAGE}


def differing(settings: Any, defaults: Any = None) -> dict[str, Any]:
    """``{dotted key: value}`` of the settings that differ from ``defaults`` (:data:`DEFAULTS`)."""
    base = {k: v for k, _, v in _walk(DEFAULTS if defaults is None else defaults, "")}
    return {k: v for k, _, v in _walk(settings, "") if base.get(k) != v}


def documented(settings: Any = None, prefix: str = "settings.") -> list[tuple[str, Any, str]]:
    """``(dotted key, default, reason)`` of every setting, in order (the ``--help`` lines)."""
    return [(k, v, f.metadata["doc"]) for k, f, v in _walk(DEFAULTS if settings is None else settings, prefix)]


# the unit a setting's name ends in, longest first; a name without one takes its check's word
UNITS = (("_rows", "rows"), ("_sigma2_per_param", "white-noise variances per parameter"), ("_c_per_min", "degC/min"),
         ("_sigma2", "white-noise variances"), ("_sigma", "white sigmas"), ("_samples", "samples"),
         ("_steps", "lattice steps"), ("_windows", "smoothing windows"), ("_s", "s"), ("_c", "degC"))
WORDS = {POSITIVE.says: "number", NONNEGATIVE.says: "number", PROBABILITY.says: "probability", SHARE.says: "share",
         FACTOR.says: "factor", COUNT.says: "count", TWO.says: "count", FOUR.says: "count", ODD.says: "count",
         SEED.says: "seed"}


def unit(name: str, f: dataclasses.Field[Any]) -> str:
    """The unit of the setting ``name`` (read off its name), or what kind of number it is."""
    found = next((u for suffix, u in UNITS if name.endswith(suffix)), None)
    return found or WORDS[f.metadata["check"].says]


def meanings(settings: Any = None) -> dict[str, str]:
    """``{settings.<section>.<key>: "[unit] reason"}`` of every setting (``tcbench diagnose --help``)."""
    return {k: f"[{unit(k.rsplit('.', 1)[-1], f)}] {f.metadata['doc']}"
            for k, f, _ in _walk(DEFAULTS if settings is None else settings, "settings.")}


def _yaml_value(value: Any) -> str:
    """``value`` as YAML that YAML 1.1 readers also take for a number (``1.0e-05``, not ``1e-05``)."""
    if isinstance(value, tuple | list):
        return "[" + ", ".join(_yaml_value(v) for v in value) + "]"
    text = repr(value)
    mantissa, e, exponent = text.partition("e")
    return f"{mantissa}.0e{exponent}" if e and "." not in mantissa else text


def yaml_lines(settings: Any = None, keys: Any = None, indent: str = "  ") -> list[str]:
    """``settings:`` as commented YAML: every section and setting of ``settings`` (default
    :data:`DEFAULTS`), or only the dotted ``keys`` (``selection.wald_threshold``), each setting
    after a comment with its unit and reason."""
    settings = DEFAULTS if settings is None else settings
    wanted = None if keys is None else set(keys)
    lines = ["settings:  # the statistics of the diagnosis (tcbench.diagnose.settings.DiagnoseSettings)"]

    def walk(obj: Any, prefix: str, depth: int) -> list[str]:
        out: list[str] = []
        pad = indent * depth
        for f in dataclasses.fields(obj):
            value, key = getattr(obj, f.name), f"{prefix}{f.name}"
            if dataclasses.is_dataclass(value):
                inner = walk(value, f"{key}.", depth + 1)
                if inner:
                    out += [f"{pad}{f.name}:  # {f.metadata['doc']}", *inner]
            elif wanted is None or key in wanted:
                why = textwrap.wrap(f"[{unit(f.name, f)}] {f.metadata['doc']}", width=116 - len(pad))
                out += [*(f"{pad}# {line}" for line in why), f"{pad}{f.name}: {_yaml_value(value)}"]
        return out

    return lines + walk(settings, "", 1)


def sections(settings: Any = None) -> list[tuple[str, str]]:
    """``(dotted key, what it sets)`` of every section, in order."""
    out: list[tuple[str, str]] = []

    def walk(obj: Any, prefix: str) -> None:
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                out.append((f"{prefix}{f.name}", f.metadata["doc"]))
                walk(value, f"{prefix}{f.name}.")

    walk(DEFAULTS if settings is None else settings, "")
    return out


DEFAULTS = DiagnoseSettings()
