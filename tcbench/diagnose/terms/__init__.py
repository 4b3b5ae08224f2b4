"""The effects of the library as the diagnosis models them: one :class:`~.base.Term` per
effect, found by id (:func:`term`). Importing the package registers every built-in term; the order of
the imports below is the order of the forward selection and of the report's candidates. Installed
terms (entry-point group ``tcbench.terms``) follow, imported on the first look-up."""

from tcbench.diagnose.terms import dynamics  # noqa: F401  (thermal_lag, temperature_rate, hysteresis)
from tcbench.diagnose.terms import clock  # noqa: F401  (warmup, aging_drift)
from tcbench.diagnose.terms import static  # noqa: F401  (temperature_cubic, accel_nonlinearity)
from tcbench.diagnose.terms import noise  # noqa: F401  (bias_instability)
from tcbench.diagnose.terms.base import (
    Extent,
    Term,
    broken_terms,
    confusable_pairs,
    is_term,
    term,
    term_source,
    terms,
)

__all__ = ["Extent", "Term", "broken_terms", "confusable_pairs", "is_term", "term", "term_source", "terms"]
