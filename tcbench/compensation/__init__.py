"""Temperature compensation: data of the MSRA tasks, baselines, the physical limit, scoring."""
