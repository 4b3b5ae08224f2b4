"""What the recording commands do with their config (``tcbench simulate|metrics|import|diagnose``):
their schemas (:mod:`.schemas`), one-line errors and output checks (:mod:`.errors`), and their work
(:mod:`.recordings`, :mod:`.diagnosis`). The job kinds of :mod:`tcbench.runner.kinds` run them;
they sit below the runner and above the diagnosis, metrics and sensors they use."""
