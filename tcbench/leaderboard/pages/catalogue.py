"""What the board pages say about each committed board folder (``leaderboards/<folder>/``) that no
CSV holds: the study and paper it belongs to, the sensor spelled out, the paper's own methods as
the boards name them, what each task tests and where the study's README is. Everything measured
comes from the committed files (:mod:`.boards`)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from tcbench import papers

REPO_URL = "https://github.com/tcbench/tcbench"  # mkdocs.yml's repo_url: links to files outside the site

SEED_000 = papers.SEED_000.markdown()
SEED_001 = papers.SEED_001.markdown()


@dataclass(frozen=True)
class Family:
    """One committed board folder and what its pages say about it."""

    folder: str  # leaderboards/<folder>/
    kind: str  # compensation, optimisation, bbob, calibration
    nav: str  # its section's name in the site's navigation
    title: str  # the pages' title: the paper and the sensor, spelled out
    readme: str  # the study's README, relative to the repository
    paper: str = ""  # the paper's citation (empty: a study of tcbench's own)
    paper_methods: tuple[str, ...] = ()  # the paper's methods as the boards name them
    # task pattern (a regex on the board's task) -> what it tests, and that in a few words for the navigation
    tasks: dict[str, tuple[str, str]] = field(default_factory=dict)
    figures: tuple[str, ...] = ()  # further figures of a board on the default tier: globs with {stem} and {task}

    def task_line(self, task: str, short: bool = False) -> str:
        """What the board of ``task`` tests (the first pattern that matches; ``{dev}``: the device);
        ``short``: in a few words."""
        for pattern, (text, brief) in self.tasks.items():
            if m := re.fullmatch(pattern, task):
                return (brief if short else text).format(**m.groupdict())
        return task


# the optimisers the seed papers propose, as the optimisation boards name them
PAPER_OPTIMISERS = ("fa", "ifa", "fa_yang", "ifa_yang", "bas", "mopso")

FAMILIES: dict[str, Family] = {f.folder: f for f in (
    Family(
        folder="paper-ifa-bp", kind="compensation", nav="Seed 000: IFA-BP on the MSRA",
        title="Seed 000 — IFA-BP compensation of a micromachined silicon resonant accelerometer (MSRA)",
        readme="experiments/paper_ifa_bp/README.md", paper=SEED_000,
        paper_methods=("IFA-BP-gd", "IFA-BP-lm"),
        tasks={r"msra_zerobias-dev(?P<dev>\d+)": ("zero-bias stability at room temperature (Table 1), device {dev}",
                                                 "Table 1: zero bias, device {dev}"),
               r"msra_fulltemp-dev(?P<dev>\d+)": ("scale factor and bias over −40…60 °C (Table 2), device {dev}",
                                                 "Table 2: full temperature, device {dev}")},
        figures=("{family_task}_*_fig*_test1.png",),
    ),
    Family(
        folder="paper-movmd-tfpf", kind="compensation", nav="Seed 001: MOVMD–TFPF on the gyroscope",
        title="Seed 001 — MOVMD–TFPF + BAS–Elman compensation of a dual-mass MEMS gyroscope",
        readme="experiments/paper_movmd_tfpf/README.md", paper=SEED_001,
        paper_methods=("MOVMD-TFPF+BAS-elman-adam",),
        tasks={r"gyro_driftnoise-dev(?P<dev>\d+)": ("drift and noise through a 14 h oven run (Fig. 19), gyro {dev}",
                                                   "Fig. 19: gyro {dev}"),
               r"gyro_driftnoise-dev(?P<dev>\d+)-bias_instability\.b=.*":
                   ("drift and noise through a 14 h oven run (Fig. 19), gyro {dev} with 3 °/h of flicker",
                    "Fig. 19: gyro {dev}, 3 °/h flicker")},
        figures=("fig19_allan_{stem}.png", "{stem}/*.png"),
    ),
    Family(
        folder="accel-chamber", kind="compensation", nav="Accelerometer through chamber cycles",
        title="Chamber cycles — the seed papers' learners on a capacitive MEMS accelerometer (tcbench's study)",
        readme="experiments/accel_chamber/README.md",
        paper_methods=("IFA-BP-gd", "IFA-BP-lm", "BAS-elman-adam"),
        tasks={r"accel_chamber-dev(?P<dev>\d+)": ("static accelerometer through 60 → −20 → 60 °C chamber cycles, "
                                                  "device {dev}", "device {dev}")},
    ),
    Family(
        folder="real-imu", kind="calibration", nav="Real IMU records",
        title="Real IMU records — offset models calibrated on real MEMS IMUs (a tofupilot IMU's chamber cycle, "
              "a PAN LSM6DSM gyroscope's cooling)",
        readme="experiments/real-imu/README.md", paper_methods=("bp_gd",),
    ),
    Family(
        folder="paper-fa-ifa", kind="optimisation", nav="Seed 000: FA against IFA",
        title="Seed 000 §2.2.3 — the firefly algorithm (FA) against the improved firefly algorithm (IFA) on "
              "Schaffer and Rastrigin (Figs. 3–4)",
        readme="experiments/paper_fa_ifa/README.md", paper=SEED_000, paper_methods=PAPER_OPTIMISERS,
    ),
    Family(
        folder="optim-suite", kind="optimisation", nav="Optimiser suite",
        title="Optimiser suite — every optimiser on eight functions in 2-D and 10-D, ZDT1–3 and DTLZ2, beside the "
              "strongest known peers",
        readme="experiments/optim_suite/README.md", paper_methods=PAPER_OPTIMISERS,
    ),
    Family(
        folder="bbob", kind="bbob", nav="BBOB f1–f24",
        title="BBOB f1–f24 — the seed papers' optimisers against the peers (COCO's noiseless functions through ioh)",
        readme="experiments/bbob/README.md", paper_methods=PAPER_OPTIMISERS,
    ),
)}

# committed folders that are no leaderboard of methods, and why they have no page here
NOT_PAGED = {
    "diagnose-concealed": "the proof set of tcbench diagnose (recordings with concealed effects), not a ranking of methods",
    "diagnose-real": "tcbench diagnose's reports on real recordings, not a ranking of methods",
    "real-pan": "the metrics of one imported real recording, not a ranking of methods",
}

# the rows of a compensation board that are references, not methods: what each is, in a few words and in full
REFERENCES = {
    "oracle": ("the physical limit", "the simulator's own model at the true die temperature: noise alone"),
    "oracle_thermometer": ("the thermometer-limited oracle",
                           "the device's model fed the temperature its thermometer's reading implies"),
    "memoriser": ("no physics", "the training runs' mean output at the same time since the start"),
}
BASELINES = {"raw": ("no compensation", "the sensor's output as recorded")}


def readme_url(path: str) -> str:
    """The address of a file of the repository (a study's README) on its host."""
    return f"{REPO_URL}/blob/main/{path}"
