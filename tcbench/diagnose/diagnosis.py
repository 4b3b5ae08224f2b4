"""``diagnose``: fit the starting model, locate the mismatch, attribute it to effects, refit.

The :class:`Diagnosis` it returns is the report: :meth:`Diagnosis.to_json` is DESIGN.md's
``report.json``; the arrays behind the plots ride along in ``series``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from joblib import Parallel, delayed

from tcbench.diagnose.attribute import (
    DETECTION_THRESHOLD,
    Attribution,
    Evidence,
    attribute,
    recheck_with_flicker,
)
from tcbench.diagnose.design import DETERMINISTIC, Designer, Model
from tcbench.diagnose.discover import OPEN_THRESHOLD, why_untestable
from tcbench.diagnose.library_findings import Extent, library_finding
from tcbench.diagnose.locate import AllanExcess, Mismatch, allan_excess, locate, why_no_allan
from tcbench.diagnose.nonmean import DEFAULT_SMOOTH_S, NonMean
from tcbench.diagnose.outliers import Outliers, find_outliers, without
from tcbench.diagnose.plan import SURROGATE, min_full_duration_s
from tcbench.diagnose.reference import Reference, reference_fit
from tcbench.diagnose.surrogate import LEVEL
from tcbench.diagnose.signals import DiagnosisData, prepare
from tcbench.diagnose.terms import is_open, open_finding, report_order, term, terms
from tcbench.diagnose.thermometer import propagated_noise, thermometer_sigma
from tcbench.sensors.recording import Recording

log = logging.getLogger(__name__)
FALSE_ALARM = 0.01  # of the mismatch scan and of the flicker test
FLICKER_FLOOR = 0.664  # Allan floor of flicker noise per unit b
TIME_EFFECTS = tuple(t.id for t in terms() if t.flicker_mimics)  # what a slow random excursion of the bias can mimic
REFERENCE_RATIO = 1.25  # final / reference held-out RMSE above which deterministic structure remains
FLICKER_TEST = ("a second power-on or a longer run: warm-up repeats after every power-on and ageing keeps "
                "its sign, a flicker excursion does neither")


@dataclass
class Series:
    """Per-sample arrays behind the plots: time, thermometer (smoothed), the held-out residual of
    the starting and of the final model, and the Allan deviations of their in-sample residuals
    against the white (plus thermometer) noise line."""

    t_s: np.ndarray
    temp_c: np.ndarray
    residual_before: np.ndarray
    residual_after: np.ndarray
    allan_before: AllanExcess | None
    allan_after: AllanExcess | None


@dataclass
class Diagnosis:
    """What the diagnosis found, in the shape of DESIGN.md's report (see :meth:`to_json`)."""

    sensor: str
    unit: str
    recording: str
    baseline: dict[str, Any]
    mismatch: list[Mismatch]
    remaining: list[Mismatch]
    effects: list[dict[str, Any]]
    final: dict[str, Any]
    noise: dict[str, float]
    candidates: list[Evidence]
    confusable: list[dict[str, Any]]
    model: dict[str, Any]
    series: Series = field(repr=False)
    reference: dict[str, Any] = field(default_factory=dict)
    statistics: dict[str, Any] = field(default_factory=dict)
    outliers: Outliers | None = None

    @property
    def deterministic_remains(self) -> bool:
        """Whether the physics-agnostic reference beats the final model by more than
        :data:`REFERENCE_RATIO` held out: temperature structure the model leaves in its residual."""
        ref = self.reference.get("rmse_heldout")
        return bool(ref) and self.final["rmse_heldout"] > REFERENCE_RATIO * ref

    @property
    def effect_ids(self) -> list[str]:
        """Ids of the effects found, in the order they were kept."""
        return [e["id"] for e in self.effects]

    @property
    def verdict(self) -> str:
        """One line: nothing missing, which effects, and whether a mismatch remains unexplained."""
        rest = ("a mismatch remains that no effect of the library explains on this recording "
                f"({len(self.remaining)} region(s) or band(s), see remaining_mismatch)")
        spikes = (f"; {self.outliers.count} isolated outlier sample(s) given zero weight (see outliers)"
                  if self.outliers is not None and self.outliers.count else "")
        library = [e["id"] for e in self.effects if e.get("library", True)]
        beyond = [f"{e['id']} ({e['shape']})" for e in self.effects
                  if not e.get("library", True) and e["id"] != "outliers"]
        if beyond:
            spikes = f"; beyond the library: {', '.join(beyond)}{spikes}"
        if not library:
            if self.remaining:
                return f"no effect of the library found, but {rest}{spikes}"
            if beyond:
                return f"no effect of the library found{spikes}"
            return f"nothing missing: the residual of the starting model is consistent with its noise{spikes}"
        named = ", ".join(library)
        pairs = "; ".join(f"{c['effects'][0]} cannot be told from {c['effects'][1]}" for c in self.confusable)
        out = f"missing: {named}" + (f" ({pairs})" if pairs else "") + (f"; {rest}" if self.remaining else "")
        if self.deterministic_remains:
            out += (f"; deterministic temperature structure remains: a generic temperature model reaches "
                    f"{self.final['rmse_heldout'] / self.reference['rmse_heldout']:.3g}x lower held-out RMSE")
        return out + spikes

    def to_json(self) -> dict[str, Any]:
        """``report.json``: plain JSON data."""
        return {
            "sensor": self.sensor, "unit": self.unit, "recording": self.recording,
            "verdict": self.verdict, "baseline": self.baseline,
            "mismatch": [m.to_dict() for m in self.mismatch],
            "remaining_mismatch": [m.to_dict() for m in self.remaining], "effects": self.effects,
            "final": self.final, "reference": self.reference, "statistics": self.statistics, "noise": self.noise,
            "candidates": [_evidence_json(e) for e in self.candidates],
            "confusable": self.confusable,
        }


def _evidence_json(e: Evidence) -> dict[str, Any]:
    out: dict[str, Any] = {"id": e.effect, "status": e.status, "reason": e.reason}
    if np.isfinite(e.gain):
        out |= {"gain_sigma2": round(float(e.gain), 2), "threshold_sigma2": float(e.threshold)}
    out |= _test_json(e)
    if e.value is not None and e.effect in DETERMINISTIC and (name := term(e.effect).param):
        out[name] = float(e.value)
    return out


def _test_json(e: Evidence) -> dict[str, Any]:
    """Which significance test decided for ``e`` and its statistic."""
    if not e.test:
        return {}
    out: dict[str, Any] = {"test": e.test}
    if np.isfinite(e.wald):
        out["robust_wald"] = round(float(e.wald), 2)
    if e.test == SURROGATE and np.isfinite(e.p_value):
        out |= {"p_value": round(float(e.p_value), 4), "level": LEVEL}
    return out


def _rmse(sse: float, n: int) -> float:
    return float(np.sqrt(sse / n))


def base_model(effects: dict[str, dict[str, float]]) -> Model:
    """The starting :class:`Model` for effects already declared (``{id: params}``, as in
    ``model.yaml``); their nonlinear parameters stay fixed, their amplitudes are refitted."""
    model = Model()
    for effect, params in effects.items():
        if effect not in DETERMINISTIC:
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
        effects["thermal_lag"] = {"tau_s": float(att.final.lag_tau_s)}
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


def _flicker(
    data: DiagnosisData, residual: np.ndarray, thermometer: np.ndarray
) -> tuple[AllanExcess | None, float | None]:
    """Allan test of a residual against white noise plus the ``thermometer`` noise the model
    inherits; the flicker coefficient ``b`` when it flattens above both."""
    ex = allan_excess(data.t_s, residual, data.white_sigma, FALSE_ALARM, estimated=True, coloured=thermometer)
    if ex is None or ex.first_over is None:
        return ex, None
    excess = np.sqrt(np.maximum(ex.adev**2 - ex.white**2, 0.0))
    return ex, float(excess[ex.first_over:].max() / FLICKER_FLOOR)


def _flicker_evidence(allan: AllanExcess | None, b: float | None, declared: bool, t_s: np.ndarray) -> Evidence:
    """How ``bias_instability`` fared; for a kept one ``gain`` is the Allan ratio at the first
    flagged tau and ``threshold`` its bound."""
    effect = "bias_instability"
    if declared:
        return Evidence(effect, "in the model", reason="declared in the starting model")
    if allan is None:
        return Evidence(effect, "not identifiable", reason=why_no_allan(t_s) or "no Allan deviation on this record")
    if b is None or allan.first_over is None:
        return Evidence(effect, "rejected", reason="the residual's Allan deviation follows the white-noise line")
    k = allan.first_over
    return Evidence(effect, "kept", float(allan.adev[k] / allan.white[k]), float(allan.bound[k]),
                    reason=f"Allan deviation above the white line from tau = {allan.tau_s[k]:.4g} s")


def diagnose(
    rec: Recording,
    *,
    sensor: str | None = None,
    declared: dict[str, dict[str, float]] | None = None,
    name: str = "",
    threshold: float = DETECTION_THRESHOLD,
    min_duration_s: float | None = None,
) -> Diagnosis:
    """Diagnose ``rec`` against the minimal model plus the effects ``declared`` already modelled
    (``{effect_id: params}``). Raises :class:`~tcbench.diagnose.signals.DiagnosisDataError` for a
    recording that cannot show anything, or that is shorter than ``min_duration_s`` (default
    :func:`~tcbench.diagnose.plan.min_full_duration_s`; :mod:`tcbench.diagnose.short_record`
    tells what a shorter one can).

    Where the thermometer smoothing fitted to the profile (:func:`~tcbench.diagnose.signals.fitted_window_s`)
    is shorter than the default, the record is diagnosed at both windows, and the default is kept
    when its final model lowers the held-out squared error by more than the open-world gain
    threshold (``statistics.thermometer_smooth_tried_s``): a window short enough to follow the
    profile's corners can leave the output's model with less to work on (on the tofupilot chamber
    cycle, 7.5 s against 120 s made the final model 1.5x worse), while on a short record with
    nothing hidden the wide window's bias at the corners offers chance gains; held-out error,
    paid for like a term, is the judge the diagnosis uses for everything else."""
    min_duration_s = min_full_duration_s() if min_duration_s is None else min_duration_s
    nonmean = NonMean.before(rec)  # a coarse thermometer staircase widens the smoothing window
    if nonmean.default_smooth_s >= DEFAULT_SMOOTH_S:
        return _diagnose(rec, nonmean, sensor, declared or {}, name, threshold, min_duration_s)
    # the two diagnoses are independent: one per core (same results as in turn, in about half the time)
    tried = Parallel(n_jobs=2)(delayed(_diagnose)(rec, nm, sensor, declared or {}, name, threshold, min_duration_s)
                               for nm in (nonmean, NonMean.before(rec, window_s=DEFAULT_SMOOTH_S)))
    fitted, default = tried
    # the default window is a model choice like a term: it must pay the open-world gain threshold
    sse = [d.final["rmse_heldout"] ** 2 * d.noise["samples"] for d in tried]
    gain = (sse[0] - sse[1]) / fitted.noise["white_sigma"] ** 2
    best = default if gain > OPEN_THRESHOLD else fitted
    best.statistics["thermometer_smooth_tried_s"] = {
        f"{d.statistics.get('thermometer_smooth_s', DEFAULT_SMOOTH_S):g}": round(float(d.final["rmse_heldout"]), 6)
        for d in tried}
    return best


def _diagnose(rec: Recording, nonmean: NonMean, sensor: str | None, declared: dict[str, dict[str, float]],
              name: str, threshold: float, min_duration_s: float) -> Diagnosis:
    """:func:`diagnose` with the non-mean detectors' thermometer reading ``nonmean``."""
    data = nonmean.prefit(prepare(rec, sensor, smooth_s=nonmean.smooth_s, min_duration_s=min_duration_s))  # output lattice; clipping
    base = base_model(declared)
    relative_sigma = nonmean.relative_sigma(data)
    outliers = _outliers(data, base, relative_sigma)  # judged at the local noise level
    data = without(data, outliers.index)  # zero weight in every fit, score and test below
    designer = Designer(data)
    log.info("diagnosing %s: %d samples, white sigma %.4g %s", name or "recording", data.n, data.white_sigma, data.unit)
    att = attribute(designer, base, threshold=threshold, open_threshold=_open_threshold(relative_sigma))
    n = data.n
    before, after = att.base_fit.heldout_residual, att.final_fit.heldout_residual
    thermo_before = propagated_noise(designer, att.base, att.base_fit.beta)
    mismatch = locate(data.t_s, data.temp_c, before, data.white_sigma, FALSE_ALARM, coloured=thermo_before)
    # The Allan test reads the in-sample residual: a held-out one carries each fold's
    # coefficient error, constant over its 15-min blocks, which looks like slow noise.
    allan_before, _ = _flicker(data, att.base_fit.residual, thermo_before)
    allan_after, b = _flicker(data, att.final_fit.residual, propagated_noise(designer, att.final, att.final_fit.beta))
    reference = reference_fit(data, att.fold, att.k)
    final_rmse = _rmse(att.final_fit.sse_heldout, n)
    structure_left = final_rmse > REFERENCE_RATIO * reference.rmse_heldout
    if structure_left:  # deterministic before stochastic: an Allan excess made by it is not flicker
        b = None
    if b is not None and len(att.final.ids) > len(base.ids):
        rechecked = recheck_with_flicker(att, b)
        # deterministic before stochastic: flicker may not take over structure the reference shows
        if rechecked is not att and _rmse(rechecked.final_fit.sse_heldout, n) <= REFERENCE_RATIO * reference.rmse_heldout:
            att = rechecked
            final_rmse = _rmse(att.final_fit.sse_heldout, n)
            after = att.final_fit.heldout_residual
            allan_after, b = _flicker(data, att.final_fit.residual,
                                      propagated_noise(designer, att.final, att.final_fit.beta))
    thermo_after = propagated_noise(designer, att.final, att.final_fit.beta)
    remaining = locate(data.t_s, data.temp_c, after, data.white_sigma, FALSE_ALARM, coloured=thermo_after)
    if b is not None:  # flicker is named: its slow excess is explained, not a remaining mismatch
        remaining = [m for m in remaining if not m.what.startswith("low-frequency")]
    core, fitted = _physical(att)
    found = [e for e in att.final.ids if e not in base.ids]
    evidence = att.evidence
    effects_out = []
    for e in found:
        evidence[e].reason = "dropping it costs more held-out error than chance allows"
        ev = {"gain_sigma2": round(float(evidence[e].gain), 2), "threshold_sigma2": float(evidence[e].threshold),
              **_test_json(evidence[e])}
        effects_out.append(open_finding(e, fitted[e], ev, data.unit) if is_open(e) else
                           library_finding(e, fitted[e], ev, Extent.of(data), evidence[e].confusable_with).to_json())
    evidence["bias_instability"] = _flicker_evidence(allan_after, b, "bias_instability" in declared, data.t_s)
    if structure_left and "bias_instability" not in declared:
        evidence["bias_instability"] = Evidence(
            "bias_instability", "not tested", reason=(
                f"deterministic temperature structure remains (the reference reaches {reference.rmse_heldout:.4g}, "
                f"the final model {final_rmse:.4g} {data.unit} held out): flicker is judged only once it is modelled"))
    confusable = [{"effects": [a, b_], "test": test} for a, b_, test in att.confusions if a in found]
    if b is not None and "bias_instability" not in declared:
        effects_out.append(library_finding("bias_instability", {"b": b}, {
            "allan_ratio": evidence["bias_instability"].gain, "bound": evidence["bias_instability"].threshold,
            "tau_s": float(allan_after.tau_s[allan_after.first_over]),  # type: ignore[union-attr,index]
        }, Extent.of(data)).to_json())
        fitted["bias_instability"] = {"b": b}
        confusable += [{"effects": [e, "bias_instability"], "test": FLICKER_TEST} for e in found if e in TIME_EFFECTS]
    if outliers.count:
        effects_out.append(outliers.finding(data.unit))
    effects_out += nonmean.postfit(data, att.final_fit.residual)  # saturation, quantisation, variance
    for effect, params in declared.items():
        fitted.setdefault(effect, dict(params))
    fitted["white_noise"] = {"density": data.white_sigma / np.sqrt(data.sample_rate_hz)}
    model = {"tcbench_model": 1, "sensor": data.sensor, "output_unit": data.unit, "core": core, "effects": fitted}
    if outliers.count:  # so that ``tcbench simulate model=`` reproduces them
        model["outliers"] = {"time_s": [float(t) for t in outliers.time_s], "size": [float(v) for v in outliers.size]}
    nonmean.write_model(model)  # so that ``tcbench simulate model=`` reproduces them too
    return Diagnosis(
        sensor=data.sensor, unit=data.unit, recording=name,
        baseline={"rmse_fit": _rmse(att.base_fit.sse_fit, n), "rmse_heldout": _rmse(att.base_fit.sse_heldout, n),
                  "model": ["minimal", *base.ids]},
        mismatch=mismatch, remaining=remaining, effects=effects_out,
        final={"rmse_fit": _rmse(att.final_fit.sse_fit, n), "rmse_heldout": _rmse(att.final_fit.sse_heldout, n),
               "model": ["minimal", *att.final.ids]},
        noise={"white_sigma": data.white_sigma, "thermometer_sigma_c": thermometer_sigma(designer),
               "samples": n, "folds": att.k},
        reference=_reference_json(reference, final_rmse, data.white_sigma),
        statistics={**(att.plan.to_json() if att.plan else {}), **nonmean.statistics(),
                    **_not_tested(att, evidence, nonmean)},
        candidates=[evidence[e] for e in (*DETERMINISTIC, *_open_ids(evidence), "bias_instability") if e in evidence],
        confusable=confusable,
        model=model,
        series=Series(data.t_s, data.temp_c, before, after, allan_before, allan_after),
        outliers=outliers,
    )


def _not_tested(att: Attribution, evidence: dict[str, Evidence], nonmean: NonMean) -> dict[str, Any]:
    """report.json ``statistics.not_tested``: ``{detector: why it could not run on this record}``
    for the library effects the record cannot show, the open-world detectors it is too short,
    too coarse or too narrow in temperature for, the Allan test and the non-mean detectors."""
    why = {e: ev.reason for e, ev in evidence.items() if ev.status in ("not identifiable", "not tested")}
    why |= {e: r for e, r in why_untestable(att.designer, att.fold).items() if e not in evidence}
    why |= nonmean.not_tested
    return {"not_tested": why} if why else {}


def _open_threshold(relative_sigma: np.ndarray | None) -> float:
    """The open-world terms' gain threshold: gains are in units of the record's RMS noise
    variance, so where the noise level changes a search that lands in the noisiest part finds
    chance gains larger by its variance ratio (up to 4x)."""
    if relative_sigma is None:
        return OPEN_THRESHOLD
    return OPEN_THRESHOLD * float(np.clip(np.max(relative_sigma) ** 2, 1.0, 4.0))


def _outliers(data: DiagnosisData, base: Model, relative_sigma: np.ndarray | None = None) -> Outliers:
    """Isolated outliers of the in-sample residual of the starting model ``base`` on ``data``
    (see :mod:`tcbench.diagnose.outliers`)."""
    x = Designer(data).matrix(base)
    beta, *_ = np.linalg.lstsq(x, data.output, rcond=None)
    return find_outliers(data.t_s, data.output - x @ beta, data.white_sigma, relative_sigma=relative_sigma)


def _reference_json(ref: Reference, final_rmse: float, sigma: float) -> dict[str, Any]:
    """report.json's ``reference``: the physics-agnostic model's held-out RMSE beside the final one."""
    return {**ref.to_json(), "rmse_heldout_sigma": ref.rmse_heldout / sigma,
            "final_over_reference": final_rmse / ref.rmse_heldout if ref.rmse_heldout > 0 else float("inf"),
            "deterministic_structure_remains": final_rmse > REFERENCE_RATIO * ref.rmse_heldout,
            "what": ("ridge regression on the smoothed thermometer temperature, its powers, first-order lags at "
                     "several time constants, dT/dt and time, under the same blocked folds")}
