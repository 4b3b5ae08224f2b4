"""Running jobs: THE job runner (:mod:`.job`), what differs per job kind (:mod:`.kinds`), the
config of a run job and its checks (:mod:`.config`, :mod:`.compensation_config`), a compensation
job prepared once (:mod:`.compensation_job`), the memory limit (:mod:`.memory`) and the ask/tell
loop (:mod:`.loop`).

Nothing is imported here (``import tcbench`` stays light): import the submodules.
"""
