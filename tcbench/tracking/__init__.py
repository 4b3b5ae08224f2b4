"""MLflow tracking: the store and the runs (:mod:`.store`), the ``tracking`` group of a config
(:mod:`.config`, a leaf), the store template (:mod:`.template`) and its file lock
(:mod:`.filelock`).

Nothing is imported here, so that :mod:`.config` is shared without importing MLflow: import the
submodules (``from tcbench.tracking import store as tracking``).
"""
