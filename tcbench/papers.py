"""The two papers tcbench comes from, cited the same way wherever a result names them.

tcbench calls them by their ids: seed 000 (Huang et al. 2022: IFA-BP compensation of a
micromachined silicon resonant accelerometer) and seed 001 (Cai et al. 2021: the parallel
MOVMD-TFPF and BAS-Elman model of a MEMS gyroscope's noise and drift).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Paper:
    """One paper: its id in tcbench, what it does in a few words, and its citation."""

    id: str
    method: str
    sensor: str
    citation: str
    doi: str = ""

    def cite(self) -> str:
        """The citation, with its DOI where one is known."""
        return f"{self.citation}{f', doi:{self.doi}' if self.doi else ''}"

    def markdown(self) -> str:
        """The citation for a markdown page: its DOI a link."""
        return f"{self.citation}{f', [doi:{self.doi}](https://doi.org/{self.doi})' if self.doi else ''}"

    def names(self) -> str:
        """The method and the sensor, then the citation: what a result of this paper's task says it is."""
        return f"{self.method} for a {self.sensor}, after {self.cite()}"


SEED_000 = Paper(
    "seed 000",
    "improved-firefly-optimised backpropagation network (IFA-BP) temperature compensation",
    "micromachined silicon resonant accelerometer (MSRA)",
    "L. Huang, L. Jiang, L. Zhao, X. Ding, 'Temperature Compensation Method Based on an Improved Firefly "
    "Algorithm Optimized Backpropagation Neural Network for Micromachined Silicon Resonant Accelerometers', "
    "Micromachines 13 (2022) 1054",
    "10.3390/mi13071054",
)
SEED_001 = Paper(
    "seed 001",
    "parallel model of MOPSO-tuned variational mode decomposition with time-frequency peak filtering "
    "(MOVMD-TFPF) and a beetle-antennae-search Elman network (BAS-Elman) removing noise and temperature drift",
    "dual-mass MEMS gyroscope",
    "Q. Cai, F. Zhao, Q. Kang, Z. Luo, D. Hu, J. Liu, H. Cao, 'A Novel Parallel Processing Model for Noise "
    "Reduction and Temperature Compensation of MEMS Gyroscope', Micromachines 12 (2021) 1285",
    "10.3390/mi12111285",
)
PAPERS = {p.id: p for p in (SEED_000, SEED_001)}
