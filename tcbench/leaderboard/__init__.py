"""Leaderboards of finished runs: the optimisation boards (:mod:`.optimisation`), the files every
board writes (:mod:`.files`, a leaf shared with :mod:`tcbench.leaderboard.compensation`), the
ECDF plots (:mod:`.ecdf`) and IOHprofiler's format (:mod:`.iohprofiler`).

Nothing is imported here: import the submodules.
"""
