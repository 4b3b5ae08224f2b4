"""``diagnose``: fit the starting model, locate the mismatch, attribute it to effects, refit.

The diagnosis is a pipeline of stages, each a function of typed inputs and outputs
(:func:`_diagnose`): prepare the record (its thermometer smoothed as the thermometer screen says),
the screens before the fit (:mod:`tcbench.diagnose.screens`: output grid, clipping, noise level,
outliers), forward selection (:mod:`tcbench.diagnose.select.attribute`), where the starting model
misses (:mod:`tcbench.diagnose.select.locate`), the screens after the final fit (flicker and the recheck
of the kept effects, the variance of the residual) and the report. The :class:`Diagnosis` it
returns is the report: :meth:`Diagnosis.to_json` is the ``report.json`` of docs/concepts/diagnosis-report.md. Every stage is
given its section of the :class:`~tcbench.diagnose.settings.DiagnoseSettings` the diagnosis runs
with.
"""

from __future__ import annotations

import logging
import multiprocessing
from dataclasses import replace
from typing import Any

import numpy as np
from joblib import Parallel, delayed

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.result import (
    Confusion,
    Diagnosis,
    FitSummary,
    Noise,
    ReferenceSummary,
    Series,
    Statistics,
    rmse,
    significance_json,
)
from tcbench.diagnose.screens import (
    FINDINGS_ORDER,
    MODEL_ORDER,
    Screened,
    ScreenInput,
    ScreenResult,
    after_fit,
    before_fit,
    run_screens,
)
from tcbench.diagnose.screens.flicker import ID as FLICKER
from tcbench.diagnose.screens.flicker import Flicker, flicker_evidence, flicker_test
from tcbench.diagnose.screens.glitches import repaired
from tcbench.diagnose.screens.noise_level import relative_sigma
from tcbench.diagnose.screens.outliers import without
from tcbench.diagnose.screens.spikes import OutliersScreen, Spikes
from tcbench.diagnose.screens.thermometer import Smoothing, ThermometerScreen, smoothing
from tcbench.diagnose.screens.thermometer_glitches import GlitchScreen, ThermometerGlitches, glitches
from tcbench.diagnose.select.attribute import Attribution, Evidence, attribute
from tcbench.diagnose.select.crossval import Fit
from tcbench.diagnose.select.design import Designer, Model, deterministic
from tcbench.diagnose.select.discover import why_untestable
from tcbench.diagnose.select.library_findings import Extent, library_finding
from tcbench.diagnose.select.locate import Mismatch, locate
from tcbench.diagnose.select.plan import min_full_duration_s
from tcbench.diagnose.select.reference import reference_fit
from tcbench.diagnose.select.thermometer_noise import propagated_noise, thermometer_sigma
from tcbench.diagnose.settings import (
    DEFAULTS,
    DiagnoseSettings,
    LocateSettings,
    SelectionSettings,
)
from tcbench.diagnose.signals import DiagnosisData, prepare
from tcbench.diagnose.terms import is_open, open_finding, report_order, temperature_transform, term
from tcbench.sensors.recording import Recording

__all__ = ["DiagnoseSettings", "Diagnosis", "Series", "base_model", "diagnose"]
log = logging.getLogger(__name__)


def base_model(effects: dict[str, dict[str, float]]) -> Model:
    """The starting :class:`Model` for effects already declared (``{id: params}``, as in
    ``model.yaml``); their nonlinear parameters stay fixed, their amplitudes are refitted."""
    model, candidates = Model(), deterministic()
    for effect, params in effects.items():
        if effect not in candidates:
            continue
        name = term(effect).param
        model = model.with_effect(effect, float(params[name]) if name else None)
    return model


def _physical(att: Attribution) -> tuple[dict[str, Any], dict[str, dict[str, float]]]:
    """Core polynomial and effect parameters of the final model, in model.yaml's form."""
    d: Designer = att.designer
    beta = att.final_fit.beta
    n_core = len(d.core_names())
    bias = [float(b) for b in beta[:3]]
    if n_core < 6:  # one input level a: the fit is output = bias(T), written as bias(T) - a plus a unit scale factor
        bias[0] -= float(np.median(d.data.input)) if d.data.input.size else 0.0
    core = {"kind": "polynomial", "centre_c": d.centre_c, "half_range_c": d.half_range_c, "bias": bias,
            "scale_factor": [float(b) for b in beta[3:6]] if n_core == 6 else [1.0]}
    effects: dict[str, dict[str, float]] = {}
    if att.final.lag_tau_s:
        lag = temperature_transform()
        effects[lag.id] = lag.params(0.0, float(att.final.lag_tau_s), d.half_range_c)
    i = n_core
    for effect, value in att.final.terms:
        m = d.columns(effect, value, att.final.lag_tau_s).shape[1]
        coef, i = beta[i:i + m], i + m
        effects[effect] = (term(effect).params(coef, value) if is_open(effect)
                           else term(effect).params(float(coef[0]), value, d.half_range_c))
    return core, effects


def _open_ids(evidence: dict[str, Evidence]) -> list[str]:
    """The open-world ids with evidence, in :func:`report_order`, further instances after the first."""
    order = list(report_order())
    ids = [e for e in evidence if is_open(e)]
    return sorted(ids, key=lambda e: (order.index(term(e).id), len(e), e))


def diagnose(
    rec: Recording,
    *,
    sensor: str | None = None,
    declared: dict[str, dict[str, float]] | None = None,
    name: str = "",
    min_duration_s: float | None = None,
    settings: DiagnoseSettings | None = None,
) -> Diagnosis:
    """Diagnose ``rec`` against the minimal model plus the effects ``declared`` already modelled
    (``{effect_id: params}``), with the statistics of ``settings`` (default
    :data:`~tcbench.diagnose.settings.DEFAULTS`). Raises
    :class:`~tcbench.diagnose.signals.DiagnosisDataError` for a recording that cannot show
    anything, or that is shorter than ``min_duration_s`` (default
    :func:`~tcbench.diagnose.select.plan.min_full_duration_s`; :mod:`tcbench.diagnose.short.short_record`
    tells what a shorter one can).

    Where the thermometer smoothing fitted to the profile (:func:`~tcbench.diagnose.signals.fitted_window_s`)
    is shorter than the default, the record is diagnosed at both windows, and the default is kept
    when its final model lowers the held-out squared error by more than the open-world gain
    threshold (``statistics.thermometer_smooth_tried_s``): a window short enough to follow the
    profile's corners can leave the output's model with less to work on (on the tofupilot chamber
    cycle, 7.5 s against 120 s made the final model 1.5x worse), while on a short record with
    nothing hidden the wide window's bias at the corners offers chance gains; held-out error,
    paid for like a term, is the judge the diagnosis uses for everything else.

    Thermometer glitches (:mod:`~tcbench.diagnose.screens.glitches`) are found first on the raw reading:
    held at the previous reading before anything is smoothed, their samples given zero weight and
    reported (``thermometer_glitches``)."""
    settings = DEFAULTS if settings is None else settings
    min_duration_s = min_full_duration_s(settings) if min_duration_s is None else min_duration_s
    default_s = settings.smoothing.default_window_s
    glitch = glitches(rec, settings.screens)  # thermometer glitches: held at the previous reading, zero weight
    rec = repaired(rec, glitch.found.index)
    fitted = smoothing(rec, settings=settings)  # a coarse thermometer staircase widens the smoothing window
    if fitted.default_smooth_s >= default_s:
        return _diagnose(rec, fitted, glitch, sensor, declared or {}, name, settings, min_duration_s)
    # the two diagnoses are independent: one per core (same results as in turn, in about half the time);
    # in turn in a sweep's worker (a daemon process, which joblib refuses to start workers from)
    workers = 1 if multiprocessing.current_process().daemon else 2
    tried = Parallel(n_jobs=workers)(delayed(_diagnose)(rec, s, glitch, sensor, declared or {}, name, settings,
                                                        min_duration_s)
                                     for s in (fitted, smoothing(rec, default_s, settings)))
    # the default window is a model choice like a term: it must pay the open-world gain threshold
    sse = [d.final.rmse_heldout ** 2 * d.noise.samples for d in tried]
    gain = (sse[0] - sse[1]) / tried[0].noise.white_sigma ** 2
    best = tried[1] if gain > settings.selection.open_threshold_sigma2 else tried[0]
    best.statistics.smooth_tried_s = {f"{d.statistics.smooth_s:g}": round(float(d.final.rmse_heldout), 6)
                                      for d in tried}
    return best


def _diagnose(rec: Recording, smooth: Smoothing, glitch: ThermometerGlitches, sensor: str | None,
              declared: dict[str, dict[str, float]], name: str, settings: DiagnoseSettings,
              min_duration_s: float) -> Diagnosis:
    """:func:`diagnose` with the thermometer smoothed as ``smooth`` says, stage by stage; the
    samples of the thermometer glitches found (``glitch``) are left out of every fit and test."""
    data = prepare(rec, sensor, smooth_s=smooth.smooth_s, min_duration_s=min_duration_s,
                   min_span_c=settings.data.min_span_c, min_samples=settings.data.min_samples)
    prepared: dict[str, ScreenResult] = {ThermometerScreen.id: smooth}
    if glitch.found.count:
        prepared[GlitchScreen.id] = glitch
    start = ScreenInput(rec, without(data, glitch.found.index), base_model(declared), frozenset(declared),
                        prepared)
    before = run_screens(before_fit(settings), start)  # output grid, clipping, noise level, outliers: zero weight
    log.info("diagnosing %s: %d samples, white sigma %.4g %s", name or "recording", before.data.n,
             before.data.white_sigma, before.data.unit)
    att = select(before.given, settings)
    mismatch = misfit(att, att.base_fit, att.base, settings.locate)  # where the starting model misses
    reference = reference_fit(before.data, att.fold, att.k, settings.reference)
    after = run_screens(after_fit(settings), replace(before.given, attribution=att, reference=reference))
    return report(name, declared, before, after, mismatch)


def select(given: ScreenInput, settings: DiagnoseSettings = DEFAULTS) -> Attribution:
    """Forward selection of the library's and the open world's terms onto the starting model,
    on the data the screens left; the open-world threshold raised where the noise level changes."""
    assert given.data is not None
    return attribute(Designer(given.data), given.base, settings=settings,
                     open_threshold=_open_threshold(relative_sigma(given), settings.selection))


def misfit(att: Attribution, fit: Fit, model: Model, settings: LocateSettings = DEFAULTS.locate) -> list[Mismatch]:
    """Where the held-out residual of ``fit`` (of ``model``) departs from its noise: white plus
    the thermometer noise the model inherits."""
    data = att.designer.data
    return locate(data.t_s, data.temp_c, fit.heldout_residual, data.white_sigma, settings,
                  coloured=propagated_noise(att.designer, model, fit.beta))


def report(name: str, declared: dict[str, dict[str, float]], before: Screened, after: Screened,
           mismatch: list[Mismatch]) -> Diagnosis:
    """The :class:`Diagnosis`: the final model's fit and findings, what every screen contributes
    (findings, model.yaml terms, statistics) and why what was not tested was not; the settings
    are the attribution's."""
    att, reference, results = after.given.attribution, after.given.reference, after.results
    assert att is not None and reference is not None
    settings = att.settings
    data, n = att.designer.data, att.designer.data.n
    flicker = results.get(FLICKER)
    final_rmse = rmse(att.final_fit.sse_heldout, n)
    core, fitted = _physical(att)
    found = [e for e in att.final.ids if e not in att.base.ids]
    evidence = att.evidence
    effects = [_found(e, evidence[e], fitted[e], data.unit, Extent.of(data), att) for e in found]
    effects += [f for key in FINDINGS_ORDER if key in results for f in results[key].findings(data.unit)]
    evidence[FLICKER] = flicker_evidence(flicker, after.not_tested.get(FLICKER), FLICKER in declared, reference,
                                         final_rmse, data.unit)
    confusable = [Confusion((a, b), test) for a, b, test in att.confusions if a in found]
    confusable += flicker.confusions(found) if isinstance(flicker, Flicker) else []
    spikes = results.get(OutliersScreen.id)
    return Diagnosis(
        sensor=data.sensor, unit=data.unit, recording=name,
        baseline=FitSummary.of(att.base_fit, n, att.base.ids), mismatch=mismatch,
        remaining=_remaining(att, flicker, settings.locate), effects=effects,
        final=FitSummary.of(att.final_fit, n, att.final.ids),
        noise=Noise(data.white_sigma, thermometer_sigma(att.designer), n, att.k),
        reference=ReferenceSummary.of(reference, final_rmse, data.white_sigma),
        statistics=Statistics(att.plan, data.smooth_s, _screen_statistics(results),
                              _not_tested(att, evidence, before, after, declared), settings=settings),
        candidates=[evidence[e] for e in (*deterministic(), *_open_ids(evidence), FLICKER) if e in evidence],
        confusable=confusable, model=_model_file(data, core, fitted, declared, results),
        series=_series(att, flicker, settings),
        outliers=spikes.found if isinstance(spikes, Spikes) else None,
    )


def _remaining(att: Attribution, flicker: ScreenResult | None, settings: LocateSettings) -> list[Mismatch]:
    """Where the final model still misses; once flicker is named, its slow excess is explained."""
    remaining = misfit(att, att.final_fit, att.final, settings)
    if isinstance(flicker, Flicker) and flicker.b is not None:
        remaining = [m for m in remaining if not m.what.startswith("low-frequency")]
    return remaining


def _model_file(data: DiagnosisData, core: dict[str, Any], fitted: dict[str, dict[str, float]],
                declared: dict[str, dict[str, float]], results: dict[str, ScreenResult]) -> dict[str, Any]:
    """model.yaml's mapping: the fitted terms and flicker, the declared ones, the white noise, and
    what the screens found, so that ``tcbench simulate model=`` reproduces it."""
    model = {"tcbench_model": 1, "sensor": data.sensor, "output_unit": data.unit, "core": core, "effects": fitted}
    if FLICKER in results:
        results[FLICKER].write_model(model)  # a term of the noise model, beside the fitted ones
    for effect, params in declared.items():
        fitted.setdefault(effect, dict(params))
    fitted["white_noise"] = {"density": data.white_sigma / np.sqrt(data.sample_rate_hz)}
    for key in (k for k in MODEL_ORDER if k in results):
        results[key].write_model(model)
    return model


def _screen_statistics(results: dict[str, ScreenResult]) -> dict[str, Any]:
    """The screens' ``statistics`` entries, in the order they ran."""
    return {k: v for r in results.values() for k, v in r.statistics().items()}


def _series(att: Attribution, flicker: ScreenResult | None, settings: DiagnoseSettings) -> Series:
    """The arrays behind the plots: held-out residuals and Allan tests of the starting and the final model."""
    data = att.designer.data
    before = flicker_test(att, att.base_fit, att.base, settings.screens.flicker.false_alarm,
                          settings.locate.min_allan_samples)[0]
    return Series(data.t_s, data.temp_c, att.base_fit.heldout_residual, att.final_fit.heldout_residual,
                  before, flicker.allan if isinstance(flicker, Flicker) else None)


def _found(effect: str, ev: Evidence, params: dict[str, float], unit: str, extent: Extent,
           att: Attribution) -> Finding:
    """The finding of a term the forward selection kept (library or open world)."""
    ev.reason = "dropping it costs more held-out error than chance allows"
    assert att.plan is not None
    said = {"gain_sigma2": round(float(ev.gain), 2), "threshold_sigma2": float(ev.threshold),
            **significance_json(ev, att.plan.test)}
    return (Finding.from_json(open_finding(effect, params, said, unit)) if is_open(effect) else
            library_finding(effect, params, said, extent, ev.confusable_with))


def _not_tested(att: Attribution, evidence: dict[str, Evidence], before: Screened, after: Screened,
                declared: dict[str, dict[str, float]]) -> dict[str, str]:
    """report.json ``statistics.not_tested``: ``{detector: why it could not run on this record}``
    for the library effects the record cannot show, the open-world detectors it is too short,
    too coarse or too narrow in temperature for, and every screen skipped (or that could not
    test it) but one declared in the starting model."""
    why = {e: ev.reason for e, ev in evidence.items() if ev.status in ("not identifiable", "not tested")}
    why |= {e: r for e, r in why_untestable(att.designer, att.fold, att.settings.detectors).items()
            if e not in evidence}
    for screen, reason in (before.not_tested | after.not_tested).items():
        if screen not in declared:
            why.setdefault(screen, reason)
    return why


def _open_threshold(relative_sigma: np.ndarray | None, selection: SelectionSettings = DEFAULTS.selection) -> float:
    """The open-world terms' gain threshold: gains are in units of the record's RMS noise
    variance, so where the noise level changes a search that lands in the noisiest part finds
    chance gains larger by its variance ratio (up to ``open_threshold_max_factor``)."""
    if relative_sigma is None:
        return selection.open_threshold_sigma2
    factor = float(np.clip(np.max(relative_sigma) ** 2, 1.0, selection.open_threshold_max_factor))
    return selection.open_threshold_sigma2 * factor
