"""A :class:`~tcbench.diagnose.result.Diagnosis` written for its reader: :mod:`~.write` puts
``report.json``, ``report.md`` (:mod:`~.markdown`), ``model.yaml``
(:mod:`tcbench.diagnose.model_file`) and the figures (:mod:`~.plots`, spectra through :mod:`~.lomb`)
into a directory; :mod:`~.explain` gives each effect found a paragraph in plain words.
"""
