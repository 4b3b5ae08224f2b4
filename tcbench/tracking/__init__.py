"""MLflow tracking: the store and the runs (:mod:`.store`), the ``tracking`` group of a config
(:mod:`.config`, a leaf) and the store template (:mod:`.template`); both the store and the
template are created under a ``filelock.FileLock`` on ``<path>.lock``.

Nothing is imported here, so that :mod:`.config` is shared without importing MLflow: import the
submodules (``from tcbench.tracking import store as tracking``).
"""
