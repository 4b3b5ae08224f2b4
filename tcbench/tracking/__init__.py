"""MLflow tracking: the store and the runs (:mod:`.store`), the ``tracking`` group of a config
(:mod:`.config`, a leaf), the store template (:mod:`.template`), the checks a command makes before
any work (:mod:`.checks`) and who hears of each run created (:mod:`.announce`, a leaf); both the
store and the template are created under a ``filelock.FileLock`` on ``<path>.lock``.

Nothing is imported here, so that the leaves are shared without importing MLflow: import the
submodules (``from tcbench.tracking import store as tracking``).
"""
