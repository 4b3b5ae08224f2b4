"""``report.md``: a :class:`~tcbench.diagnose.diagnosis.Diagnosis` in plain words for a reader.

Every finding of ``effects`` (the contract of :mod:`tcbench.diagnose.findings`, library effect or
not) is rendered the same way, whatever its id: a row of the findings table (id, shape, library,
where) and a section with its shape and what that shape looks like (docs/concepts/diagnosis-report.md, shapes), its scalar
parameters with units (a term's from its :attr:`~tcbench.diagnose.terms.Term.units`), where
(:func:`format_where`: instants in s and h from the start, periods in s and min, bands in degC,
levels in the finding's ``params`` ``unit`` or the output unit), the evidence, what it cannot be
told from, confirm-with, a table of its listed values (lists of one length in ``params`` and
``evidence``, such as outlier times and sizes) and its explanation.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.result import Diagnosis
from tcbench.diagnose.select.attribute import Evidence
from tcbench.diagnose.select.significance import SURROGATE
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, differing
from tcbench.diagnose.terms import Term, is_term, term, terms

PLOT_CAPTIONS = {
    "residuals": "Held-out residual of the starting and the final model against time and temperature "
                 "(faint: samples; line: 5-min means; shaded: located mismatch; grey: +-1 white sigma).",
    "allan": "Allan deviation of the held-out residual against the white (+ thermometer) noise line "
             "and the flagging bound.",
    "evidence": "Penalised held-out gain of each candidate effect against the detection threshold.",
    "spectrum": "Spectrum of the held-out residual of the starting and the final model (periodogram, or "
                "Lomb-Scargle for a record of bursts) against the white-noise level; dashed: located lines.",
    "output": "Output and thermometer against time; dashed: located instants, dash-dotted: located levels.",
}
LOCATED_NOTE = ("Findings are marked from their `where`: dashed vertical lines at located instants, strips (and "
                "shading, when narrower than the recording's range) over located temperature bands.")


def _g(x: Any, digits: int = 4) -> str:
    """A number in ``digits`` significant figures; a dash for missing or non-finite values."""
    if x is None:
        return "-"
    x = float(x)
    return f"{x:.{digits}g}" if math.isfinite(x) else "-"


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
    return lines


SCREEN_UNITS = {"amplitude": "{unit}", "density": "{unit}/sqrt(Hz)"}  # of a finding that is no term (a screen's)


def _term(effect: str) -> Term | None:
    """The term of ``effect``, or None for a finding that is no term (a screen's)."""
    return term(effect) if is_term(effect) else None


def _param(name: str, value: float, unit: str, t: Term | None = None) -> str:
    """``name = value unit`` with the unit read off the parameter's name (``tau_s`` also in min)
    or, where the name does not say it, off its term ``t`` (None: a screen's finding)."""
    v = _g(value)
    if name.endswith("_s") and not name.endswith("_per_s"):
        return f"{name} = {v} s ({_g(value / 60.0, 3)} min)"
    if t is not None:
        named = t.unit_of(name, unit)
    else:
        named = SCREEN_UNITS[name].format(unit=unit) if name in SCREEN_UNITS else None
    if named is not None:
        return f"{name} = {v} {named}"
    if name.endswith("_c"):
        return f"{name} = {v} degC"
    return f"{name} = {v}"


def _gain_cell(e: Evidence) -> str:
    if not math.isfinite(e.gain):
        return "-"
    t = _term(e.effect)
    if t is not None and t.gain_name:
        return f"{t.gain_name} {_g(e.gain, 3)} (bound {_g(e.threshold, 3)})"
    return f"{_g(e.gain)} (threshold {_g(e.threshold)})"


def _gain_note() -> str:
    """What the gain column holds for the terms not judged by the held-out gain."""
    return " ".join(f"For {t.id} the number is the {t.gain_name} against its bound instead."
                    for t in terms() if t.gain_name)


def _test_cell(e: Evidence) -> str:
    if e.test == SURROGATE:
        return f"surrogate p = {_g(e.p_value, 3)}"
    return f"Wald {_g(e.wald, 3)}" if math.isfinite(e.wald) else "-"


def _value_cell(e: Evidence) -> str:
    if e.value is None:
        return "-"
    t = _term(e.effect)
    name = t.param if t is not None else None
    return _g(e.value) if name is None else _param(name, e.value, "", t)


SHAPE_SIGNATURE = {  # docs/concepts/diagnosis-report.md, shapes: what each shape looks like in the residual
    "step": "a bias jump at one instant, flat before and after",
    "periodic": "a spectral line, often unrelated to temperature",
    "trend": "a slow drift against time, not temperature",
    "transient": "a decay after power-on or after a handling event",
    "temperature_function": "a smooth function of the thermometer beyond the model's order",
    "temperature_dynamics": "depends on how the temperature got there: rate, lag, heating against cooling",
    "input_function": "depends on the applied input",
    "variance": "the noise level changes with temperature or time",
    "saturation": "a flat ceiling or floor",
    "outliers": "isolated samples far off the rest",
    "quantisation": "output or thermometer on a grid",
    "noise": "random structure left after every deterministic term",
}
MAX_LISTED_WHERE = 10  # instants or lines listed in a ``Where`` line; the rest counted


def _numbers(x: Any) -> list[float]:
    """A number or a list of numbers as a list."""
    return [float(v) for v in x] if isinstance(x, (list, tuple)) else [float(x)]


def _listed(items: list[str], what: str) -> str:
    if len(items) <= MAX_LISTED_WHERE:
        return ", ".join(items)
    return ", ".join(items[:MAX_LISTED_WHERE]) + f", ... ({len(items)} {what} in all)"


def _duration(seconds: float) -> str:
    """``seconds`` in s, with min or h beside when it is long."""
    if abs(seconds) >= 7200.0:
        return f"{_g(seconds)} s ({_g(seconds / 3600.0, 3)} h)"
    if abs(seconds) >= 120.0:
        return f"{_g(seconds)} s ({_g(seconds / 60.0, 3)} min)"
    return f"{_g(seconds)} s"


def format_where(where: dict[str, Any], unit: str, t0: float) -> str:
    """A finding's ``where`` in words: instants in s and h from the start of the recording,
    periods in s and min, temperature bands in degC, levels with ``unit``."""
    parts = []
    if "time_s" in where:
        times = [f"{_g(t, 8)} s ({_g((t - t0) / 3600.0, 4)} h from the start)" for t in _numbers(where["time_s"])]
        parts.append("at t = " + _listed(times, "instants"))
    if "period_s" in where:
        periods = [f"{_g(p)} s ({_g(p / 60.0, 3)} min)" for p in _numbers(where["period_s"])]
        parts.append("period " + _listed(periods, "periods"))
    if "frequency_hz" in where:
        freqs = [f"{_g(f)} Hz" + (f" (period {_g(1.0 / f / 60.0, 3)} min)" if f > 0 else "")
                 for f in _numbers(where["frequency_hz"])]
        parts.append("frequency " + _listed(freqs, "lines"))
    if "temperature_c" in where:
        low, high = where["temperature_c"]
        parts.append(f"temperature band {_g(low)} to {_g(high)} degC")
    if "level" in where:
        parts.append("level " + _listed([f"{_g(v)} {unit}" for v in _numbers(where["level"])], "levels"))
    return "; ".join(parts) if parts else "not localised: the whole record"


def _evidence_text(ev: dict[str, Any], settings: DiagnoseSettings = DEFAULTS) -> str:
    """Evidence in words: the held-out gain and its test (at ``settings``' Wald threshold and
    surrogate level), the Allan ratio, the outlier bound, or any other evidence as ``name = value`` pairs."""
    if "allan_ratio" in ev:
        return (f"Allan deviation {_g(ev['allan_ratio'], 3)} times the white-noise line from tau = "
                f"{_g(ev.get('tau_s'))} s, above the bound {_g(ev.get('bound'), 3)}.")
    if "gain_sigma2" in ev:
        line = (f"dropping it raises the held-out squared error by {_g(ev['gain_sigma2'])} sigma^2 "
                f"(penalised), against a threshold of {_g(ev.get('threshold_sigma2'))} sigma^2")
        if ev.get("test") == SURROGATE:
            return (line + f"; significant by the {SURROGATE} test, p = {_g(ev.get('p_value'), 3)} <= "
                    f"{_g(settings.surrogate.level)}.")
        if "robust_wald" in ev:
            return line + f"; cluster-robust Wald {_g(ev['robust_wald'], 3)} > {_g(settings.selection.wald_threshold)}."
        if ev.get("test"):
            return line + f"; test: {ev['test']}."
        return line + "."
    if "bound_z" in ev:
        return (f"robust z beyond the bound of {_g(ev['bound_z'], 3)} (robust sigma {_g(ev.get('robust_sigma'))}; "
                f"false-alarm probability {_g(ev.get('false_alarm'))} over the record); test: {ev.get('test', '-')}.")
    pairs = [f"{k} = {_g(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v}"
             for k, v in ev.items() if not isinstance(v, (list, tuple, dict))]
    return "; ".join(pairs) + "." if pairs else "-"


def _scalar_params(params: dict[str, Any], unit: str, t: Term | None = None) -> str:
    """The scalar ``params`` of a finding (of term ``t``; None: a screen's) with their units."""
    out = []
    for k, v in params.items():
        if isinstance(v, bool) or isinstance(v, (list, tuple, dict)):
            continue
        out.append(_param(k, v, unit, t) if isinstance(v, (int, float)) else f"{k} = {v}")
    return "; ".join(out) or "-"


def _listed_table(f: Finding, unit: str, t0: float) -> list[str]:
    """Lists of one length in ``params`` and ``evidence`` (instants, sizes, scores) as a table,
    with hours from the start beside ``time_s``."""
    columns = {k: v for k, v in f.params.items() if isinstance(v, (list, tuple)) and v
               and all(isinstance(x, (int, float)) for x in v)}
    if not columns:
        return []
    n = len(next(iter(columns.values())))
    columns = {k: v for k, v in columns.items() if len(v) == n}
    columns |= {k: v for k, v in f.evidence.items() if isinstance(v, (list, tuple)) and len(v) == n
                and all(isinstance(x, (int, float)) for x in v)}
    header, cols = [], []
    for k, v in columns.items():
        header.append("time (s)" if k == "time_s" else f"{k} ({unit})" if k in ("size", "amplitude", "level") else k)
        cols.append([_g(x, 8 if k == "time_s" else 4) for x in v])
        if k == "time_s":
            header.append("time (h from start)")
            cols.append([_g((x - t0) / 3600.0, 4) for x in v])
    rows = list(zip(*cols, strict=True))
    out = _table(header, rows)
    count = f.params.get("count")
    if isinstance(count, int) and count > n:
        out.append(f"({n} largest of {count} listed.)")
    return [*out, ""]


def finding_section(f: Finding, unit: str, t0: float, settings: DiagnoseSettings = DEFAULTS) -> list[str]:
    """One finding of the report contract (any ``id``): shape, library or not, parameters,
    where, evidence (read at ``settings``), what it cannot be told from, confirm-with, listed
    values and explanation."""
    kind = "library effect" if f.library else "not a library effect"
    unit_here = str(f.params.get("unit", unit))
    out = [f"### {f.id} ({f.shape}, {kind})", "",
           f"- Shape: {f.shape}" + (f" ({SHAPE_SIGNATURE[f.shape]})" if f.shape in SHAPE_SIGNATURE else ""),
           f"- Parameters: {_scalar_params(f.params, unit_here, _term(f.id))}",
           f"- Where: {format_where(f.where, unit_here, t0)}",
           f"- Evidence: {_evidence_text(f.evidence, settings)}"]
    if f.extra.get("confusable_with"):
        out.append(f"- Cannot be told from: {', '.join(f.extra['confusable_with'])} (see below)")
    out += [f"- Confirm with: {f.confirm_with}", ""]
    out += _listed_table(f, unit_here, t0)
    return [*out, f.explanation, ""]


def findings_table(effects: list[Finding], unit: str, t0: float) -> list[str]:
    """One row per finding: id, shape, library, where."""
    return _table(["finding", "shape", "library", "where"],
                  ([f.id, f.shape, "yes" if f.library else "no",
                    format_where(f.where, str(f.params.get("unit", unit)), t0)] for f in effects))


def not_tested_section(not_tested: dict[str, str]) -> list[str]:
    """The "Not tested on this record" list: each detector that could not run, and why."""
    if not not_tested:
        return []
    return ["## Not tested on this record", "",
            *(f"- **{name}**: {reason}." for name, reason in not_tested.items()), ""]


def settings_note(settings: DiagnoseSettings) -> list[str]:
    """The settings of ``tcbench diagnose`` that differ from the defaults, one ``key = value``
    each (report.json ``statistics.settings`` has them all); nothing at the defaults."""
    changed = differing(settings)
    if not changed:
        return []
    said = ", ".join(f"`{k} = {list(v) if isinstance(v, tuple) else v}` (default {_default(k)})"
                     for k, v in changed.items())
    return [f"Settings that differ from the defaults: {said}.", ""]


def _default(key: str) -> Any:
    value: Any = DEFAULTS
    for part in key.split("."):
        value = getattr(value, part)
    return list(value) if isinstance(value, tuple) else value


def render_markdown(d: Diagnosis, plots: dict[str, str]) -> str:
    """The human-readable report of ``d``; ``plots`` maps plot name to its file name, relative to
    the report (as returned by :func:`tcbench.diagnose.report.plots.write_plots`)."""
    sigma = float(d.noise.white_sigma)
    settings = d.statistics.settings
    t0 = float(d.series.t_s[0]) if len(d.series.t_s) else 0.0
    out = [f"# Diagnosis of {d.recording or 'recording'} ({d.sensor})", "",
           f"**Verdict:** {d.verdict}", "", *d.preface()]

    out += ["## Fit", "",
            (f"White noise sigma {_g(sigma)} {d.unit} per sample, {int(d.noise.samples)} samples, "
             f"{int(d.noise.folds)}-fold blocked cross-validation. The held-out RMSE of a model that "
             "misses nothing is close to 1 sigma."), ""]
    rows = []
    for label, fit in (("baseline", d.baseline), ("final", d.final)):
        rows.append([label, ", ".join(fit.model), _g(fit.rmse_fit), _g(fit.rmse_heldout),
                     f"{_g(fit.rmse_heldout / sigma, 3)} sigma"])
    ref = d.reference
    if ref is not None:
        rows.append(["reference (no physics)", f"ridge on {len(ref.terms)} temperature terms", _g(ref.rmse_fit),
                     _g(ref.rmse_heldout), f"{_g(ref.rmse_heldout / sigma, 3)} sigma"])
    out += _table(["model", "terms", f"RMSE fit ({d.unit})", f"RMSE held-out ({d.unit})", "held-out / white sigma"],
                  rows)
    out.append("")
    if ref is not None:
        ratio = ref.final_over_reference
        out += [(f"The reference is a {ref.what} ({', '.join(ref.terms)}); it names no physics and says how "
                 f"far a model driven by the thermometer can go on this recording. Final / reference held-out RMSE: "
                 f"**{_g(ratio, 3)}**"
                 + (f", above {_g(settings.reference.structure_ratio)}: deterministic temperature structure remains in the final "
                    "residual, so bias instability is not judged." if ref.deterministic_structure_remains else ".")),
                ""]
    plan = d.statistics.plan
    why = (f"the recording holds {plan.n_clusters} clusters of {_g(plan.cluster_s)} s, too few for the "
           "cluster-robust Wald test, so effects are tested against surrogates with the spectrum of the "
           f"candidate model's residual (p <= {_g(settings.surrogate.level)})" if plan.test.name == SURROGATE else
           f"{plan.n_clusters} clusters of {_g(plan.cluster_s)} s for the cluster-robust Wald test (an effect that "
           "removes most of the excess error and fails it is tried by the surrogate test instead)")
    out += [(f"Statistics sized to this recording: blocks of {_g(plan.block_s)} s in {plan.k} interleaved "
             f"folds; {why}."), ""]
    out += settings_note(settings)

    out += ["## Where the starting model misses", ""]
    if d.mismatch:
        out += [("Departures of the starting model's held-out residual from white noise (times in hours from "
                 "the start of the recording)."), ""]
        out += _table(["from (h)", "to (h)", "what", "statistic", "threshold"],
                      ([_g((m.t_start_s - t0) / 3600.0, 3), _g((m.t_end_s - t0) / 3600.0, 3), m.what,
                        _g(m.statistic, 3), _g(m.threshold, 3)] for m in d.mismatch))
    else:
        out.append("No region departs from white noise.")
    out.append("")
    if d.remaining:
        out += ["## What remains after the refit", "",
                ("The final model's held-out residual still departs from noise here; no effect of the library "
                 "explains it beyond chance on this recording:"), ""]
        out += _table(["from (h)", "to (h)", "what", "statistic", "threshold"],
                      ([_g((m.t_start_s - t0) / 3600.0, 3), _g((m.t_end_s - t0) / 3600.0, 3), m.what,
                        _g(m.statistic, 3), _g(m.threshold, 3)] for m in d.remaining))
        out.append("")

    out += ["## Effects found", ""]
    if not d.effects:
        noise = [t.id for t in terms() if not t.deterministic]  # judged from the residual, after the selection
        flicker = next((e for e in d.candidates if e.effect in noise), None)
        name = (flicker.effect if flicker else noise[0]).replace("_", " ")
        allan = ("the residual's Allan deviation follows the white-noise line" if flicker and flicker.status == "rejected"
                 else f"{name}: {flicker.reason}" if flicker else f"{name} was not tested")
        out += [("Nothing missing: no candidate effect improves the held-out error by more than chance allows; "
                 f"{allan}."), ""]
    if d.effects:
        out += [*findings_table(d.effects, d.unit, t0), ""]
    for effect in d.effects:
        out += finding_section(effect, d.unit, t0, settings)

    out += ["## Effects this recording cannot tell apart", ""]
    if d.confusable:
        for c in d.confusable:
            a, b = c.effects
            out.append(f"- **{a}** cannot be told from **{b}**. A test that would separate them: {c.test}.")
    else:
        out.append("None.")
    out.append("")

    out += ["## All candidates", "",
            ("Gain: drop in held-out squared error, in units of the white-noise variance, less "
             f"{_g(settings.selection.penalty_sigma2_per_param)} per added "
             "parameter. An effect is kept when its gain exceeds the threshold and it is significant: its "
             f"cluster-robust Wald statistic exceeds {_g(settings.selection.wald_threshold)}, or, where that test "
             f"cannot be used, the surrogate test's p-value is at most {_g(settings.surrogate.level)} (the column "
             f"says which). {_gain_note()}"), ""]
    out += _table(["effect", "status", "gain (sigma^2)", "significance", "best parameter", "reason"],
                  ([e.effect, e.status, _gain_cell(e), _test_cell(e), _value_cell(e), e.reason]
                   for e in d.candidates))
    out.append("")
    out += not_tested_section(d.statistics.not_tested)

    if plots:
        out += ["## Plots", ""]
        for name, filename in plots.items():
            caption = PLOT_CAPTIONS.get(name, name) + (f" {LOCATED_NOTE}" if name == "residuals" and d.effects else "")
            out += [f"![{name}]({filename})", "", caption, ""]
    return "\n".join(out).rstrip() + "\n"
