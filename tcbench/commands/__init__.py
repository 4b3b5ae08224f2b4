"""The registry of every command (:mod:`.registry`), and what the commands do with their config:
their schemas (:mod:`.schemas`), one-line errors and output checks (:mod:`.errors`), and their work
(:mod:`.recordings`, :mod:`.diagnosis`, :mod:`.calibration`, :mod:`.export`, :mod:`.listing`). The
job kinds of :mod:`tcbench.runner.kinds` run them; they sit below the runner and above the
diagnosis, metrics and sensors they use."""
