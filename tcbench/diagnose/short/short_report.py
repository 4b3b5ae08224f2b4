"""Write a short-record report (:class:`~tcbench.diagnose.short.short_record.ShortRecordReport`) to a
directory: ``report.json`` and ``report.md``, staged and moved into ``out`` only when both exist."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tcbench.diagnose.report.markdown import _g, _table
from tcbench.diagnose.report.write import _plain
from tcbench.diagnose.short.short_record import ShortRecordReport
from tcbench.diagnose.short.short_tests import ShortTest
from tcbench.staging import staged_dir


def _numbers(t: ShortTest, unit: str) -> str:
    """A test's statistic, interval and p-value in words."""
    v = t.values
    level = f"{100 * v.get('ci_level', 0):g} %"
    if t.id == "temperature_slope":
        return (f"{_g(v['slope_per_c'])} {unit}/degC, {level} interval [{_g(v['ci_low'])}, {_g(v['ci_high'])}], "
                f"p = {_g(v['p_value'], 3)} (standard error {_g(v['se'])}, {_g(v['se'] / v['se_white_noise_formula'], 3)}x "
                f"the white-noise formula's; {_g(v['effective_samples'], 3)} effective of {v['samples']} samples, "
                f"{_g(v['dof'], 3)} degrees of freedom)"
                + (f"; cannot be told from {v['confusable_with']}" if "confusable_with" in v else ""))
    if t.id == "level_step":
        where = ""
        if "nearest_ramp_start_s" in v:
            where = (f"; {'at' if v['at_ramp_start'] else 'not at'} the ramp start at "
                     f"{_g(v['nearest_ramp_start_s'])} s")
        return (f"{_g(v['size'])} {unit} ({_g(v['size_white_sigmas'], 3)} white sigmas) at {_g(v['time_s'])} s{where}, "
                f"{level} interval [{_g(v['ci_low'])}, {_g(v['ci_high'])}] at that time, search-wide p = "
                f"{_g(v['p_value'], 3)} ({v['surrogates']} noise surrogates)")
    if t.id == "white_noise":
        out = f"sigma {_g(v['white_sigma'])} {unit} per sample, density {_g(v['density_per_sqrt_hz'])} {unit}/sqrt(Hz)"
        if "tau_max_s" in v:
            out += (f"; Allan deviation {'white up to' if 'excess_from_tau_s' not in v else 'above the white line from'}"
                    f" tau = {_g(v.get('excess_from_tau_s', v['tau_max_s']))} s")
        return out
    return ""


def render_short_markdown(report: ShortRecordReport) -> str:
    """``report.md`` of a short record."""
    lines = [f"# Short-record report: {report.recording or 'recording'}", "",
             f"{report.sensor}, output in {report.unit}: {_g(report.duration_s)} s, {report.samples} samples at "
             f"{_g(report.sample_rate_hz)} Hz, temperature span {_g(report.temperature_span_c, 3)} degC "
             f"(thermometer smoothed over {_g(report.smooth_s, 3)} s).", "",
             f"A full diagnosis needs {_g(report.full_duration_s)} s; this record gets the tests its length allows, "
             f"each at level {report.to_json()['level']:g}.", "",
             f"**Verdict**: {report.verdict}", ""]
    if report.native_rate is not None:
        lines += report.native_rate.markdown(report.unit)
    lines += ["## Tests run", ""]
    rows = [(t.id, t.status, _numbers(t, report.unit), t.what) for t in report.tests if t.ran]
    lines += _table(["test", "verdict", "statistic", "what"], rows) if rows else ["None."]
    if report.findings:
        lines += ["", "## Found", ""]
        lines += [f"- **{f.id}**: {f.explanation.rstrip('.')}; confirm with {f.confirm_with.rstrip('.')}."
                  for f in report.findings]
    lines += ["", "## Not run on this record", ""]
    missing = [f"- **{t.id}**: {t.reason}." for t in report.tests if not t.ran]
    missing += [f"- **{r['id']}**: needs {_g(r['needs_s'])} s ({_g(r['needs_s'] / 60.0, 3)} min): {r['what']}."
                for r in report.needs_more_time]
    lines += missing or ["Nothing."]
    return "\n".join(lines) + "\n"


def write_short_report(report: ShortRecordReport, out: str | Path, inputs: Sequence[str | Path] = (),
                       overwrite: bool = True, replaced: list[Path] | None = None) -> dict[str, Path]:
    """Write ``report.json`` and ``report.md`` into ``out``, neither over one of ``inputs`` nor over
    an existing file without ``overwrite`` (the paths replaced appended to ``replaced``); name -> path."""
    out = Path(out)
    doc: dict[str, Any] = _plain(report.to_json())
    with staged_dir(out, inputs, overwrite, replaced) as tmp:
        (tmp / "report.json").write_text(json.dumps(doc, indent=2) + "\n")
        (tmp / "report.md").write_text(render_short_markdown(report))
    return {name: out / name for name in ("report.json", "report.md")}
