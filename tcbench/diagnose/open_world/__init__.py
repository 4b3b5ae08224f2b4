"""Open-world recordings for testing ``tcbench diagnose``: a mismatch outside the effect library
hidden under the noise (:mod:`.recordings`), and the fixed rules that score a report against it
(:mod:`.scoring`)."""

from tcbench.diagnose.open_world.recordings import (
    ADDITIVE,
    DETERMINISTIC,
    KINDS,
    RATIO,
    SENSORS,
    SHAPE,
    OpenWorld,
    open_world_recording,
)
from tcbench.diagnose.open_world.scoring import (
    Score,
    finding_matches,
    score,
    time_tolerance_s,
    where_matches,
)

__all__ = [
    "ADDITIVE",
    "DETERMINISTIC",
    "KINDS",
    "RATIO",
    "SENSORS",
    "SHAPE",
    "OpenWorld",
    "Score",
    "finding_matches",
    "open_world_recording",
    "score",
    "time_tolerance_s",
    "where_matches",
]
