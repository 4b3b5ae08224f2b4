"""A record of any rate and length: what a diagnosis of its rows costs (:mod:`~.cost`) and, for a
record of more rows than a diagnosis takes, the thermal terms fitted on bin means and the noise
terms measured on every sample (:mod:`~.native_rate`, :func:`~.native_rate.diagnose_any_rate`).
"""
