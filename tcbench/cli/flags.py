"""The command-line flags tcbench passes to Hydra or reads itself: a leaf that the entry point
(:mod:`tcbench.cli.main`) and the Hydra glue (:mod:`tcbench.cli.app`) both read, so neither
imports the other for them."""

from __future__ import annotations

HYDRA_INFO_FLAGS = {"--help", "-h", "--hydra-help", "--info", "-i", "--cfg", "-c", "--shell-completion", "-sc"}
HYDRA_FLAGS = HYDRA_INFO_FLAGS | {
    "--version", "--resolve", "-p", "--package", "-r", "--run", "-m", "--multirun", "-cp", "--config-path",
    "-cn", "--config-name", "-cd", "--config-dir", "--experimental-rerun",
}
HELP_FLAGS = {"-h", "--help"}
# Hydra flags followed by a value; those that change where configs come from make tcbench
# skip its up-front check (each job still validates its own config).
VALUE_FLAGS = {"-cp", "--config-path", "-cn", "--config-name", "-cd", "--config-dir", "-p", "--package", "--experimental-rerun"}
CONFIG_SOURCE_FLAGS = {"-cp", "--config-path", "-cn", "--config-name", "-cd", "--config-dir", "--experimental-rerun"}
CFG_CHOICES = ("job", "hydra", "all")  # the values of Hydra's --cfg
# flags every key=value command takes for a key of its schema: ``--out DIR`` is ``out=DIR``
KEY_FLAGS = {"--out": ("out", "DIR")}
