"""Datasets that prove ``tcbench diagnose``: generated recordings with a known truth (an effect of
the library or a structure outside it hidden under the noise, controls with nothing hidden) and
the real recordings read from the repository's ``data/real/``. The diagnosis never imports them."""
