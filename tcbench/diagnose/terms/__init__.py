"""The effects the diagnosis models: one :class:`~.base.Term` per effect of the library, and one
:class:`~.open_base.OpenTerm` per structure outside it (docs/concepts/diagnosis-report.md, shapes), found by id (:func:`term`).
Importing the package registers every built-in term; the order of the imports below is the order
of the forward selection and of the report's candidates (for the open-world terms: of a round's
search, the report ordering them by shape). Installed terms (entry-point group ``tcbench.terms``)
follow, imported on the first look-up."""

from tcbench.diagnose.terms import dynamics  # noqa: F401  (thermal_lag, temperature_rate, hysteresis)
from tcbench.diagnose.terms import clock  # noqa: F401  (warmup, aging_drift)
from tcbench.diagnose.terms import static  # noqa: F401  (temperature_cubic, accel_nonlinearity)
from tcbench.diagnose.terms import noise  # noqa: F401  (bias_instability)
from tcbench.diagnose.terms import events  # noqa: F401  (bias_step, transient)
from tcbench.diagnose.terms import cycles  # noqa: F401  (periodic, gated_periodic, duty_cycle)
from tcbench.diagnose.terms import temperature_shapes  # noqa: F401  (temperature_bump, second_node)
from tcbench.diagnose.terms.base import (
    Extent,
    Term,
    broken_terms,
    confusable_pairs,
    is_term,
    term,
    temperature_transform,
    term_source,
    terms,
)
from tcbench.diagnose.terms.open_base import OpenTerm, Search, is_open, open_finding, open_term, report_order

__all__ = ["Extent", "OpenTerm", "Search", "Term", "broken_terms", "confusable_pairs", "is_open", "is_term",
           "open_finding", "open_term", "report_order", "temperature_transform", "term", "term_source", "terms"]
