"""A thermal-gradient stress term for tcbench: the output moves with the square of the
temperature rate (:mod:`.temperature_rate_squared`: the effect simulated and the term diagnosed)."""
