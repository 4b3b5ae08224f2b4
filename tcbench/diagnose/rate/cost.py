"""How long a diagnosis of a record will take, and how much memory, known from its rows before
it starts.

Every stage of a diagnosis works on every sample (fits of the model and of each candidate effect
at each value of its grid in each cross-validation fold, the detectors, the tests), and a longer
record gives it more to find. Measured with ``benchmarks/diagnose_scaling.py`` (a simulated gyro
oven record of 6 h sampled at 1e4..1e6 rows, one diagnosis in a fresh process on one core;
``benchmarks/RESULTS.md``), the CPU seconds grow as ``rows ** EXPONENT`` and scatter by a factor
of two or three about that line with what the record holds; :data:`SECONDS_PER_1E5` is the envelope (the
slowest measurement on the fitted slope), so the estimate errs long. The peak memory of one
diagnosis grows by :data:`BYTES_PER_ROW` per row.

A record of more rows than ``settings.rate.max_rows`` (10^5) is diagnosed on 1 s bin means, its
noise measured on every sample (:mod:`tcbench.diagnose.rate.native_rate`), so these figures apply to
the bins. :data:`tcbench.commands.schemas.DIAGNOSE_MAX_ROWS` is the most rows ``tcbench diagnose``
runs on unless ``max_rows=`` says otherwise: about 8 min of one core and 3 GB, where 10^7 rows would
take 1.2 h and 30 GB (more than most machines have; the two thermometer windows a diagnosis may
try run at once, each with its own memory).
"""

from __future__ import annotations

SECONDS_PER_1E5 = 49.0  # the envelope's CPU seconds at 1e5 rows (the fit: 23 s)
EXPONENT = 0.98  # the fitted slope of log(CPU seconds) on log(rows), 1e4..1e6 rows
BASE_BYTES = 250e6  # peak memory of a diagnosis of few rows (the libraries, the report)
BYTES_PER_ROW = 3.0e3  # and its growth per row (1e4..2e5 rows)


def estimated_s(rows: int) -> float:
    """The CPU seconds a diagnosis of ``rows`` rows is estimated to take on one core."""
    return SECONDS_PER_1E5 * (max(rows, 1) / 1e5) ** EXPONENT


def estimated_bytes(rows: int) -> float:
    """The peak memory (bytes) of one diagnosis of ``rows`` rows."""
    return BASE_BYTES + BYTES_PER_ROW * max(rows, 0)


def duration_text(seconds: float) -> str:
    """``40 s``, ``12 min``, ``3.5 h``, ``2.1 days``: a duration as a person reads it."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def size_text(size: float) -> str:
    """``300 MB``, ``3.2 GB``: a size in bytes as a person reads it."""
    return f"{size / 1e6:.0f} MB" if size < 1e9 else f"{size / 1e9:.1f} GB"
