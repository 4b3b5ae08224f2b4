"""Write a diagnosis to a directory: ``report.json``, ``report.md``, ``model.yaml`` and plots.

Everything is written into a temporary sibling directory first and moved into ``out`` only when
all files exist, so a failure leaves ``out`` as it was.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tcbench.diagnose.model_file import ModelSpec, parse_model, write_model
from tcbench.diagnose.report.markdown import render_markdown
from tcbench.diagnose.report.plots import write_plots
from tcbench.diagnose.result import Diagnosis
from tcbench.staging import staged_dir


def _plain(value: Any) -> Any:
    """JSON-ready copy: numpy scalars to Python numbers, non-finite floats to None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def model_spec(diag: Diagnosis) -> ModelSpec:
    """The fitted model of a diagnosis, as ``model.yaml`` holds it."""
    return parse_model(_plain(diag.model), "model.yaml")


def write_report(diag: Diagnosis, out: str | Path, inputs: Sequence[str | Path] = (),
                 with_plots: bool = True, overwrite: bool = True, replaced: list[Path] | None = None) -> dict[str, Path]:
    """Write the report files into ``out`` (created if needed), none of them over one of
    ``inputs``, nor over an existing file without ``overwrite`` (:func:`~tcbench.staging.staged_dir`:
    the paths replaced are appended to ``replaced``); returns name -> path. ``with_plots=False``
    leaves out the figures."""
    out = Path(out)
    with staged_dir(out, inputs, overwrite, replaced) as tmp:
        (tmp / "report.json").write_text(json.dumps(_plain(diag.to_json()), indent=2) + "\n")
        write_model(model_spec(diag), tmp / "model.yaml")
        plots = write_plots(diag, tmp) if with_plots else {}
        (tmp / "report.md").write_text(render_markdown(diag, plots))
        names = sorted(item.name for item in tmp.iterdir())
    return {name: out / name for name in names}
