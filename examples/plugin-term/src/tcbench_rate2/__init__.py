"""A thermal-gradient stress term for tcbench: the output moves with the square of the
temperature rate (:mod:`.effect` simulates it, :mod:`.term` diagnoses it)."""
