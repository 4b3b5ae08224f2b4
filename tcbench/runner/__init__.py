"""Running jobs: THE job runner (:mod:`.job`), what differs per job kind (:mod:`.kinds`), the
config of a run job and its checks (:mod:`.config`, :mod:`.compensation_config`), a compensation
or optimisation job prepared once (:mod:`.compensation_job`, :mod:`.optimisation_job`) on the env
its plan check built (:mod:`.kept_env`), the memory limit (:mod:`.memory`) and the ask/tell loop
(:mod:`.loop`).

Nothing is imported here (``import tcbench`` stays light): import the submodules.
"""
