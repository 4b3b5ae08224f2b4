"""A record too short for a full diagnosis (:func:`tcbench.diagnose.select.plan.min_full_duration_s`):
the tests it still supports (:mod:`~.short_tests`), run on it (:mod:`~.short_record`) and written
as ``report.json`` and ``report.md`` (:mod:`~.short_report`).
"""
