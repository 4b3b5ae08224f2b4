"""tcbench's Hydra sweeper and launcher (see :mod:`.launcher`)."""
