"""``tcbench quickstart`` end to end at the test size: the compensation table with the oracle
row, the diagnosis naming the hidden effect, the files it names, and its runs in MLflow."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import mlflow
import pytest
import yaml

from tcbench.cli import main
from tcbench.cli.quickstart import activate_command
from tcbench.commands.schemas import QuickstartConfig


def test_the_quickstart_defaults_are_the_experiment_s() -> None:
    """``tcbench quickstart`` and ``tcbench run -m experiment=quickstart`` run the same sweep."""
    from importlib.resources import files

    cfg = yaml.safe_load(files("tcbench.conf").joinpath("experiment/quickstart.yaml").read_text())
    defaults = QuickstartConfig()
    assert cfg["hydra"]["sweeper"]["params"]["seed"] == f"range({defaults.seeds})"
    assert cfg["budget"] == defaults.budget == 510


def test_quickstart_end_to_end(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["quickstart", "seeds=2", "budget=60", "epochs=100"]) == 0  # two short trainings
    out = capsys.readouterr().out

    assert out.startswith("tcbench: a benchmark for temperature compensation")
    assert "IFA-BP trained 2 times" in out and "not the paper's result" in out
    table = out.split("Leaderboard msra_zerobias-dev0")[1].split("== 2.")[0]
    methods = [ln.split()[1] for ln in table.splitlines() if re.match(r"\s+\d+\s", ln)]
    assert sorted(methods) == ["IFA-BP-gd", "lagpoly", "memoriser", "oracle", "poly3", "poly3_runs", "raw"]
    assert re.search(r"\n\s+\d+\s+oracle\s+2\s+0\s+\S+\s+\S+–\S+\s+1\s", table), table  # its own draws' ratio: 1
    runs = [ln.split()[2] for ln in table.splitlines() if re.match(r"\s+\d+\s", ln)]
    assert runs == ["2"] * 7  # every row on the trainings' two draws
    assert "physical limit" in table
    assert "IFA-BP-gd = the paper's method" in table and "gradient descent (gd)" in table  # the legend under it

    assert "Verdict: missing: thermal_lag" in out and "the hidden effect was thermal_lag: found" in out
    assert "found thermal_lag" in out and "where: temperature " in out and "in sigma" in out
    assert "Next steps" in out and ".venv/bin/" not in out.split("Next steps")[1]
    assert "(cluster-robust Wald: the effect's coefficients" in out
    assert f"activate it once per shell: {activate_command(Path(sys.prefix), workdir)}" in out
    assert "micromachined silicon resonant accelerometer (MSRA)" in out and "doi:10.3390/mi13071054" in out
    # Hydra's lines (each job's summary, the sweep's progress) and the diagnosis job's own summary are in the
    # log, not between the results
    assert "[HYDRA]" not in out and "][INFO]" not in out and "logged to MLflow run" not in out
    log = (workdir / "tcbench-quickstart" / "quickstart.log").read_text()
    assert log.count("Launching") == 3 and "IFA-BP-gd-msra_zerobias-dev0-s1: zb_zero_start_ug" in log
    assert "diagnosed tcbench-quickstart/recordings/concealed-msra-thermal_lag-0.csv" in log
    assert "logged to MLflow run" in log

    named = [Path(p) for line in out.splitlines() if line.startswith(("Leaderboard: ", "Diagnosis report"))
             for p in line.split(": ", 1)[1].split(", ")]
    names = {p.name for p in named}
    assert {"msra_zerobias-dev0.md", "msra_zerobias-dev0.png", "report.md", "report.json", "residuals.png"} <= names
    assert all(p.is_file() and p.stat().st_size > 0 for p in named)
    assert all(p.is_relative_to(workdir / "tcbench-quickstart") for p in named)

    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    exp = client.get_experiment_by_name("quickstart")
    runs = client.search_runs([exp.experiment_id])
    assert all(r.info.status == "FINISHED" for r in runs)
    kinds = sorted(r.data.tags["tcbench.kind"] for r in runs)
    assert kinds == ["compensation"] * 14 + ["diagnosis"]  # seven rows on two draws each
    trained = [r for r in runs if r.data.tags["tcbench.method"] == "IFA-BP-gd"]
    assert {r.data.params["budget"] for r in trained} == {"60"} and {r.data.params["learner.epochs"] for r in trained} == {"100"}
    assert len({r.data.tags["tcbench.sweep_id"] for r in runs}) == 1
    (diag,) = [r for r in runs if r.data.tags["tcbench.kind"] == "diagnosis"]
    assert diag.data.tags["tcbench.effects_found"] == "thermal_lag"
    m = diag.data.metrics
    assert m["rmse_heldout_after_sigma"] < m["rmse_heldout_before_sigma"] and m["effects_found"] == 1
    assert {"report.md", "report.json", "model.yaml"} <= {a.path for a in client.list_artifacts(diag.info.run_id)}


@pytest.mark.slow
def test_full_quickstart_ranks_ifa_bp_between_the_oracle_and_poly(workdir: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """The full size (about two minutes on 2 cores), tested on new power-ons: the lag-aware
    polynomial is the best method, the paper's IFA-BP beats the pooled cubic and stays above the
    physical limit; the numbers the README quotes."""
    assert main(["quickstart"]) == 0
    out = capsys.readouterr().out
    rows = {ln.split()[1]: ln.split() for ln in out.split("Leaderboard msra_zerobias-dev0")[1].split("== 2.")[0]
            .splitlines() if re.match(r"\s+\d+\s", ln)}
    order = ("oracle", "lagpoly", "poly3_runs", "memoriser", "IFA-BP-gd", "poly3", "raw")
    assert [rows[m][0] for m in order] == [str(i) for i in range(1, 8)]
    assert rows["IFA-BP-gd"][4] == "50.1" and rows["poly3"][4] == "53.5" and rows["oracle"][4] == "7.6"
    assert rows["poly3_runs"][4] == "40.3" and rows["memoriser"][4] == "49.4" and rows["lagpoly"][4] == "22.9"
    assert "IFA-BP trained 5 times" in out and "minimal + thermal_lag" in out
