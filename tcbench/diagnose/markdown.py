"""``report.md``: a :class:`~tcbench.diagnose.diagnosis.Diagnosis` in plain words for a reader."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

from tcbench.diagnose.attribute import WALD_THRESHOLD, Evidence
from tcbench.diagnose.diagnosis import REFERENCE_RATIO, Diagnosis
from tcbench.diagnose.plan import SURROGATE
from tcbench.diagnose.surrogate import LEVEL

PLOT_CAPTIONS = {
    "residuals": "Held-out residual of the starting and the final model against time and temperature "
                 "(faint: samples; line: 5-min means; shaded: located mismatch; grey: +-1 white sigma).",
    "allan": "Allan deviation of the held-out residual against the white (+ thermometer) noise line "
             "and the flagging bound.",
    "evidence": "Penalised held-out gain of each candidate effect against the detection threshold.",
}


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


def _param(name: str, value: float, unit: str) -> str:
    """``name = value unit`` with the unit read off the parameter's name (``tau_s`` also in min)."""
    v = _g(value)
    if name.endswith("_s") and not name.endswith("_per_s"):
        return f"{name} = {v} s ({_g(value / 60.0, 3)} min)"
    units = {
        "width_c": "degC", "amplitude": unit, "coef_per_c_per_s": f"{unit} per degC/s",
        "rate_per_h": f"{unit}/h", "c3_per_c3": f"{unit}/degC^3", "k2_per_g2": f"{unit}/g^2",
        "b": f"{unit} (flicker coefficient)", "density": f"{unit}/sqrt(Hz)",
    }
    if name in units:
        return f"{name} = {v} {units[name]}"
    if name.endswith("_c"):
        return f"{name} = {v} degC"
    return f"{name} = {v}"


def _evidence_line(effect: dict[str, Any]) -> str:
    ev = effect.get("evidence", {})
    if "allan_ratio" in ev:
        return (f"Allan deviation {_g(ev['allan_ratio'], 3)} times the white-noise line from tau = "
                f"{_g(ev.get('tau_s'))} s, above the bound {_g(ev.get('bound'), 3)}.")
    if "gain_sigma2" in ev:
        line = (f"dropping it raises the held-out squared error by {_g(ev['gain_sigma2'])} sigma^2 "
                f"(penalised), against a threshold of {_g(ev.get('threshold_sigma2'))} sigma^2")
        if ev.get("test") == SURROGATE:
            return line + f"; significant by the {SURROGATE} test, p = {_g(ev.get('p_value'), 3)} <= {_g(LEVEL)}."
        if "robust_wald" in ev:
            return line + f"; cluster-robust Wald {_g(ev['robust_wald'], 3)} > {_g(WALD_THRESHOLD)}."
        return line + "."
    return "-"


def _gain_cell(e: Evidence) -> str:
    if e.effect == "bias_instability":
        return f"Allan ratio {_g(e.gain, 3)} (bound {_g(e.threshold, 3)})" if math.isfinite(e.gain) else "-"
    return f"{_g(e.gain)} (threshold {_g(e.threshold)})" if math.isfinite(e.gain) else "-"


def _test_cell(e: Evidence) -> str:
    if e.test == SURROGATE:
        return f"surrogate p = {_g(e.p_value, 3)}"
    return f"Wald {_g(e.wald, 3)}" if math.isfinite(e.wald) else "-"


def _value_cell(e: Evidence) -> str:
    if e.value is None:
        return "-"
    name = {"thermal_lag": "tau_s", "warmup": "tau_s", "hysteresis": "width_c"}.get(e.effect)
    return _g(e.value) if name is None else _param(name, e.value, "")


def _outliers_section(effect: dict[str, Any], unit: str, t0: float) -> list[str]:
    """The ``outliers`` finding: count, bound and a table of the listed samples."""
    p, ev = effect["params"], effect["evidence"]
    out = ["### outliers (not a library effect)", "",
           (f"- {p['count']} isolated sample(s) beyond the bound of {_g(ev['bound_z'], 3)} robust sigma "
            f"(robust sigma {_g(ev['robust_sigma'])} {unit}; false-alarm probability {_g(ev['false_alarm'])} over "
            "the record); given zero weight in every fit, held-out score and test."),
           f"- Confirm with: {effect['confirm_with']}", ""]
    out += _table(["time (s)", "time (h from start)", f"size ({unit})", "robust z"],
                  ([_g(t, 8), _g((t - t0) / 3600.0, 4), _g(s), _g(z, 3)]
                   for t, s, z in zip(p["time_s"], p["size"], ev["robust_z"], strict=True)))
    if p["count"] > len(p["time_s"]):
        out.append(f"({len(p['time_s'])} largest of {p['count']} listed.)")
    return [*out, "", effect["explanation"], ""]


def render_markdown(d: Diagnosis, plots: dict[str, str]) -> str:
    """The human-readable report of ``d``; ``plots`` maps plot name to its file name, relative to
    the report (as returned by :func:`tcbench.diagnose.plots.write_plots`)."""
    sigma = float(d.noise["white_sigma"])
    t0 = float(d.series.t_s[0]) if len(d.series.t_s) else 0.0
    out = [f"# Diagnosis of {d.recording or 'recording'} ({d.sensor})", "",
           f"**Verdict:** {d.verdict}", ""]

    out += ["## Fit", "",
            (f"White noise sigma {_g(sigma)} {d.unit} per sample, {int(d.noise.get('samples', 0))} samples, "
             f"{int(d.noise.get('folds', 0))}-fold blocked cross-validation. The held-out RMSE of a model that "
             "misses nothing is close to 1 sigma."), ""]
    rows = []
    for label, fit in (("baseline", d.baseline), ("final", d.final)):
        rows.append([label, ", ".join(fit.get("model", [])), _g(fit["rmse_fit"]), _g(fit["rmse_heldout"]),
                     f"{_g(fit['rmse_heldout'] / sigma, 3)} sigma"])
    ref = d.reference
    if ref:
        rows.append(["reference (no physics)", f"ridge on {len(ref['terms'])} temperature terms", _g(ref["rmse_fit"]),
                     _g(ref["rmse_heldout"]), f"{_g(ref['rmse_heldout'] / sigma, 3)} sigma"])
    out += _table(["model", "terms", f"RMSE fit ({d.unit})", f"RMSE held-out ({d.unit})", "held-out / white sigma"],
                  rows)
    out.append("")
    if ref:
        ratio = ref["final_over_reference"]
        out += [(f"The reference is a {ref['what']} ({', '.join(ref['terms'])}); it names no physics and says how "
                 f"far a model driven by the thermometer can go on this recording. Final / reference held-out RMSE: "
                 f"**{_g(ratio, 3)}**"
                 + (f", above {_g(REFERENCE_RATIO)}: deterministic temperature structure remains in the final "
                    "residual, so bias instability is not judged." if ref["deterministic_structure_remains"] else ".")),
                ""]
    st = d.statistics
    if st:
        test = st["significance_test"]
        why = (f"the recording holds {st['clusters']} clusters of {_g(st['cluster_s'])} s, too few for the "
               "cluster-robust Wald test, so effects are tested against surrogates with the spectrum of the "
               f"candidate model's residual (p <= {_g(LEVEL)})" if test == SURROGATE else
               f"{st['clusters']} clusters of {_g(st['cluster_s'])} s for the cluster-robust Wald test (an effect that "
               "removes most of the excess error and fails it is tried by the surrogate test instead)")
        out += [(f"Statistics sized to this recording: blocks of {_g(st['cv_block_s'])} s in {st['folds']} interleaved "
                 f"folds; {why}."), ""]

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
        flicker = next((e for e in d.candidates if e.effect == "bias_instability"), None)
        allan = ("the residual's Allan deviation follows the white-noise line" if flicker and flicker.status == "rejected"
                 else f"bias instability: {flicker.reason}" if flicker else "bias instability was not tested")
        out += [("Nothing missing: no candidate effect improves the held-out error by more than chance allows; "
                 f"{allan}."), ""]
    for effect in d.effects:
        if effect.get("shape") == "outliers":
            out += _outliers_section(effect, d.unit, t0)
            continue
        out += [f"### {effect['id']}", ""]
        params = "; ".join(_param(k, v, d.unit) for k, v in effect.get("params", {}).items())
        out += [f"- Parameters: {params or '-'}", f"- Evidence: {_evidence_line(effect)}"]
        if effect.get("confusable_with"):
            out.append(f"- Cannot be told from: {', '.join(effect['confusable_with'])} (see below)")
        out += ["", effect.get("explanation", ""), ""]

    out += ["## Effects this recording cannot tell apart", ""]
    if d.confusable:
        for c in d.confusable:
            a, b = c["effects"]
            out.append(f"- **{a}** cannot be told from **{b}**. A test that would separate them: {c['test']}.")
    else:
        out.append("None.")
    out.append("")

    out += ["## All candidates", "",
            ("Gain: drop in held-out squared error, in units of the white-noise variance, less 2 per added "
             "parameter. An effect is kept when its gain exceeds the threshold and it is significant: its "
             f"cluster-robust Wald statistic exceeds {_g(WALD_THRESHOLD)}, or, where that test cannot be used, "
             f"the surrogate test's p-value is at most {_g(LEVEL)} (the column says which). For bias_instability "
             "the number is the Allan ratio against its bound instead."), ""]
    out += _table(["effect", "status", "gain (sigma^2)", "significance", "best parameter", "reason"],
                  ([e.effect, e.status, _gain_cell(e), _test_cell(e), _value_cell(e), e.reason]
                   for e in d.candidates))
    out.append("")

    if plots:
        out += ["## Plots", ""]
        for name, filename in plots.items():
            caption = PLOT_CAPTIONS.get(name, name)
            out += [f"![{name}]({filename})", "", caption, ""]
    return "\n".join(out).rstrip() + "\n"
