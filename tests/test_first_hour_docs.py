"""What a new user reads in the first hour says what it means: seed 001 cited in full wherever
it is cited, the quickstart's names (IFA-BP-gd, zb_zero_start_ug, the cluster-robust Wald test)
explained where they are printed and on the quickstart's page, and a board's "–" p-value said."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest

from tcbench.papers import SEED_000, SEED_001

ROOT = Path(__file__).resolve().parents[1]
INDEX = ROOT / "docs" / "index.md"
TITLE_001 = "A Novel Parallel Processing Model for Noise Reduction and Temperature Compensation of MEMS Gyroscope"


def _flat(text: str) -> str:
    return " ".join(text.replace("*", "").split())


def test_seed_001_is_cited_with_its_authors_title_and_doi_everywhere() -> None:
    from tcbench.leaderboard.compensation import task_line
    from tcbench.leaderboard.pages import catalogue

    assert SEED_001.doi == "10.3390/mi12111285" and TITLE_001 in SEED_001.citation
    assert SEED_001.citation.startswith("Q. Cai, ") and SEED_001.citation.endswith("Micromachines 12 (2021) 1285")
    link = "[doi:10.3390/mi12111285](https://doi.org/10.3390/mi12111285)"
    for page in (ROOT / "README.md", INDEX):
        text = _flat(page.read_text(encoding="utf-8"))
        assert TITLE_001 in text and link in text and "Cai" in text, page.name
    assert catalogue.SEED_001 == SEED_001.markdown() and link in catalogue.SEED_001
    assert catalogue.SEED_000 == SEED_000.markdown()
    assert SEED_001.cite() in task_line("gyro")
    boards = sorted((ROOT / "leaderboards" / "paper-movmd-tfpf").glob("*.md"))
    cited = [b for b in boards if "seed 001:" in b.read_text(encoding="utf-8")]
    assert cited and all(SEED_001.cite() in b.read_text(encoding="utf-8") for b in cited)


def test_the_quickstart_page_explains_what_the_quickstart_prints() -> None:
    from tcbench.cli.quickstart import TABLE_LEGEND, TEST_LEGEND
    from tcbench.diagnose.select.significance import ROBUST_WALD

    text = INDEX.read_text(encoding="utf-8")
    assert TABLE_LEGEND in text  # the legend under the table, as printed
    assert "IFA-BP-gd" in TABLE_LEGEND and "gradient descent" in TABLE_LEGEND
    assert ROBUST_WALD in TEST_LEGEND and _flat(TEST_LEGEND[ROBUST_WALD]) in _flat(text)
    assert "`zb_zero_start_ug`" in text and "from power-on" in text


def _runs(method: str, zb0_ug: np.ndarray) -> pd.DataFrame:
    n = zb0_ug.size
    return pd.DataFrame({"method": method, "status": "FINISHED", "seed": np.arange(n), "error_message": "",
                         "zb_zero_start_ug": zb0_ug, "raw_zb_zero_start_ug": 232.0,
                         "zb_after_20min_ug": zb0_ug, "raw_zb_after_20min_ug": 200.0,
                         "zb_after_30min_ug": zb0_ug, "raw_zb_after_30min_ug": 150.0,
                         "train_rmse_ug": np.ones(n)})


def test_a_board_says_why_p_vs_next_is_a_dash_and_labels_its_plot(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """Under six shared seeds the p-value is "–"; the board's key says why, and the plot's axis
    is the metric in words with its unit, not its column name."""
    from matplotlib.axes import Axes

    from tcbench.leaderboard import compensation as comp
    from tcbench.leaderboard.labels import column_label

    matplotlib.use("Agg")
    rng = np.random.default_rng(0)
    runs = pd.concat([_runs("oracle", np.array([6.9])), _runs("IFA-BP-gd", rng.uniform(90, 110, 5)),
                      _runs("raw", np.array([232.0]))], ignore_index=True)
    board = comp.CompensationBoard("msra_zerobias-dev0", "roomtemp", comp.summarise(runs, "roomtemp"), runs)
    assert board.table["p_vs_next"].isna().all()  # no pair shares six seeds
    said: list[str] = []
    monkeypatch.setattr(Axes, "set_ylabel", lambda self, label, *a, **k: said.append(label))
    paths = comp.write(board, tmp_path, "a test")
    text = paths["md"].read_text(encoding="utf-8")
    assert "| – |" in text and "p_vs_next is – where the row and the next share fewer than 6 pairs" in text
    assert "6" in column_label("p_vs_next") and "–" in column_label("p_vs_next")
    assert said == ["zero-bias stability from power-on (µg)"]


@pytest.mark.parametrize(("split", "title"), [("new_profile", "msra_zerobias-dev0 (new_profile): "),
                                              ("next_run", "msra_zerobias-dev0: ")])
def test_a_tier_boards_plot_names_its_tier(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, split: str,
                                          title: str) -> None:
    """A tier's plot sits beside the default tier's in the same folder: its title says which it is."""
    from matplotlib.axes import Axes

    from tcbench.leaderboard import compensation as comp

    matplotlib.use("Agg")
    runs = pd.concat([_runs("IFA-BP-gd", np.linspace(90.0, 110.0, 6)), _runs("raw", np.full(6, 232.0))],
                     ignore_index=True)
    board = comp.CompensationBoard("msra_zerobias-dev0", "roomtemp", comp.summarise(runs, "roomtemp"), runs,
                                   split=split)
    said: list[str] = []
    monkeypatch.setattr(Axes, "set_title", lambda self, label, *a, **k: said.append(label))
    comp.write(board, tmp_path, "a test")
    assert len(said) == 1 and said[0].startswith(title)
