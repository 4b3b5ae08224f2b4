"""Which effects the model misses: the forward selection and the statistics it decides with.

:mod:`~.attribute` adds, round by round, the effect (or open-world term, :mod:`~.discover`) whose
columns (:mod:`~.design`) lower the held-out error of blocked cross-validation (:mod:`~.crossval`)
most, as :mod:`~.score` fits each model and scores each candidate, if it passes the significance test (:mod:`~.significance`: the robust Wald test or the
spectral surrogates of :mod:`~.surrogate`, standard errors from :mod:`~.spectral_se`) that the
statistics plan (:mod:`~.plan`) sizes to the record; :mod:`~.evidence` keeps how each candidate
fared. Beside it: where a residual departs from white noise (:mod:`~.locate`), the
physics-agnostic reference (:mod:`~.reference`), the thermometer's noise carried into the output
(:mod:`~.thermometer_noise`) and the library's effects as findings (:mod:`~.library_findings`).
Imports :mod:`tcbench.diagnose.terms` and the shared modules below it, nothing above.
"""
