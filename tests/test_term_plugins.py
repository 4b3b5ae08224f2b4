"""Diagnosis terms from other packages: the example plugin-term package end to end, and broken ones.
The commands run in this process with the plugins installed here (:func:`cli_here.install_here`:
the diagnosis reads its terms from the registry at each use); one ``python -m tcbench`` without
the plugin is the command-line smoke test, and the example's own tests run in a process of their own."""

from __future__ import annotations

import json
from collections.abc import Iterator
import os
import subprocess
import sys
from pathlib import Path

import pytest
from cli_here import end_reused_workers, install_here
from cli_here import tcbench as here
from plugin_site import fake_distribution, install_example, tcbench

from tcbench.diagnose.terms import term_source
from tcbench.diagnose.terms import terms as all_terms
from tcbench.sensors.effects import Hysteresis, effect_class, make_effect

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plugin-term"
TERM = "temperature_rate_squared"
OTHERS = "without=[bias_instability,temperature_cubic,temperature_rate]"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example plugin installed (not editable) into a directory put on PYTHONPATH."""
    return install_example("plugin-term", tmp_path_factory)


@pytest.fixture
def installed(site: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The example plugin installed in this process too, for this test."""
    install_here(monkeypatch, site)
    yield site
    end_reused_workers()


def _simulate(coef: float, name: str, cwd: Path) -> Path:
    run = here("simulate", "sensor=gyro", "protocol=oven", "device_seed=1", "seed=2",
                  f"effects.{TERM}.coef_per_c2_per_min2={coef}", OTHERS, "protocol_params.sample_rate_hz=0.1",
                  "out=rec", f"name={name}", "metrics=false", "tracking.enabled=false", cwd=cwd)
    assert run.returncode == 0, run.stderr
    return cwd / "rec" / f"{name}.csv"


def _diagnose(recording: Path, out: str, cwd: Path) -> dict:
    run = here("diagnose", f"recording={recording}", f"out={out}", "tracking.enabled=false", cwd=cwd)
    assert run.returncode == 0, run.stderr
    return json.loads((cwd / out / "report.json").read_text())


def test_listed_with_its_shape(installed: Path, tmp_path: Path) -> None:
    listed = here("list", "what=terms", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    line = next(x for x in listed.stdout.splitlines() if x.split()[:1] == [TERM])
    assert "temperature_dynamics" in line and "(from tcbench-rate2)" in line
    assert "thermal_lag" in listed.stdout and "BROKEN" not in listed.stdout
    open_world = [x for x in listed.stdout.splitlines() if x.endswith("(open world, from tcbench)")]
    assert [x.split()[0] for x in open_world] == ["bias_step", "transient", "periodic", "gated_periodic", "duty_cycle",
                                                  "temperature_bump", "second_node"]  # after the library's
    assert listed.stdout.splitlines().index(line) < listed.stdout.splitlines().index(open_world[0])


def test_diagnose_names_the_plugin_effect_only_where_it_is(installed: Path, tmp_path: Path) -> None:
    report = _diagnose(_simulate(0.05, "with", tmp_path), "with", tmp_path)
    found = {e["id"]: e for e in report["effects"]}
    assert TERM in found and found[TERM]["library"] is True
    assert found[TERM]["params"]["coef_per_c2_per_min2"] == pytest.approx(0.05, rel=0.2)  # 0.0463 at 0.1 Hz
    assert "(degC/min)^2" in found[TERM]["explanation"]
    without = _diagnose(_simulate(0.0, "without", tmp_path), "without", tmp_path)
    assert TERM not in {e["id"] for e in without["effects"]}
    assert TERM in {c["id"] for c in without["candidates"]}  # tried like a library term, rejected
    # the fitted model simulates with the plugin's effect, and without the plugin says what is missing
    again = here("simulate", "model=with/model.yaml", "protocol=oven", "out=again", "metrics=false",
                 "tracking.enabled=false", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    bare = tcbench("simulate",  # the command-line smoke test, in a process without the plugin
                    "model=with/model.yaml", "protocol=oven", "out=bare", "metrics=false",
                   "tracking.enabled=false", cwd=tmp_path, path=tmp_path / "nothing")
    assert bare.returncode != 0 and f"unknown effect {TERM!r}" in bare.stderr


def _library_terms_and_their_source() -> list[tuple[str, str]]:
    return [(t.id, term_source(t.id)) for t in all_terms()]


@pytest.mark.worker_processes
def test_the_diagnosis_workers_have_the_plugin_term(installed: Path) -> None:
    """A diagnosis tries its two smoothing windows on two joblib workers: the plugin's term is a
    candidate there as in this process (its folder on their path, its entry point read anew)."""
    from joblib import Parallel, delayed

    here_terms = _library_terms_and_their_source()
    assert (TERM, "tcbench-rate2") in here_terms
    in_workers = Parallel(n_jobs=2)(delayed(_library_terms_and_their_source)() for _ in range(2))
    assert in_workers == [here_terms, here_terms]


def test_example_plugin_own_tests(site: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(site)}
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(EXAMPLE / "tests")],
                         env=env, capture_output=True, text=True, timeout=300, cwd=site)
    assert out.returncode == 0, out.stdout + out.stderr


@pytest.mark.parametrize(("entry", "error"), [
    ("no_such_module_xyz:Nope", "ModuleNotFoundError: No module named 'no_such_module_xyz'"),
    ("tcbench.sensors.effects:ThermalLag", "does not name a tcbench.diagnose.terms.base.Term subclass"),
])
def test_broken_term_plugin_is_listed_and_harmless(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, entry: str,
                                                    error: str) -> None:
    site = tmp_path / "site"
    site.mkdir()
    fake_distribution(site, "broken_terms", f"[tcbench.terms]\nbroken_term = {entry}\n")
    install_here(monkeypatch, site)
    listed = here("list", "what=terms", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    assert "broken_term              BROKEN: " in listed.stdout and error in listed.stdout
    assert "bias_instability" in listed.stdout
    assert here("list", "what=sensors", cwd=tmp_path).returncode == 0


def test_a_term_clashing_with_a_builtin_or_without_its_effect_is_broken(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    site = tmp_path / "site"
    site.mkdir()
    code = (
        "from dataclasses import dataclass\n"
        "from typing import ClassVar\n"
        "from tcbench.diagnose.terms import Term\n"
        "from tcbench.sensors.effects import Effect, Hysteresis\n"
        "class Clash(Term):\n"
        "    id = 'hysteresis'\n"
        "    effect = Hysteresis\n"
        "    def explanation(self, params, unit): return ''\n"
        "    def params(self, coef, value, half_range_c): return {}\n"
        "@dataclass(frozen=True)\n"
        "class Orphan(Effect):\n"
        "    id: ClassVar[str] = 'orphan'\n"
        "class OrphanTerm(Term):\n"
        "    id = 'orphan'\n"
        "    effect = Orphan\n"
        "    def explanation(self, params, unit): return ''\n"
        "    def params(self, coef, value, half_range_c): return {}\n"
    )
    code_clash, code_orphan = code.split("@dataclass")[0], "from tcbench.sensors.effects import Effect\n" + (
        "from dataclasses import dataclass\nfrom typing import ClassVar\nfrom tcbench.diagnose.terms import Term\n"
        "@dataclass" + code.split("@dataclass")[1])
    fake_distribution(site, "clash", "[tcbench.terms]\nhysteresis = clash_mod:Clash\n", "clash_mod", code_clash)
    fake_distribution(site, "orphan", "[tcbench.terms]\norphan = orphan_mod:OrphanTerm\n", "orphan_mod", code_orphan)
    install_here(monkeypatch, site)
    listed = here("list", "what=terms", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    assert "ValueError: term 'hysteresis' is registered twice" in listed.stdout
    assert "ValueError: term 'orphan' models effect orphan_mod.Orphan, which the effect library does not know" \
        in listed.stdout
    terms = [x.split()[0] for x in listed.stdout.splitlines()[1:] if "BROKEN" not in x]
    assert terms.count("hysteresis") == 1 and "orphan" not in terms
    assert [t.id for t in all_terms()][-1] == "bias_instability" and term_source("hysteresis") == "tcbench"


def test_broken_effect_plugin_is_listed_and_harmless(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    site = tmp_path / "site"
    site.mkdir()
    fake_distribution(site, "bad_effects", "[tcbench.effects]\nhysteresis = tcbench.sensors.effects:Hysteresis\n"
                       "gone = no_such_module_xyz:Gone\n")
    install_here(monkeypatch, site)
    listed = here("list", "what=terms", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    assert "hysteresis               BROKEN effect: ValueError: effect 'hysteresis' is a built-in effect" in listed.stdout
    assert "gone                     BROKEN effect: ModuleNotFoundError" in listed.stdout
    assert effect_class("hysteresis") is Hysteresis
    with pytest.raises(ValueError, match="^effect 'gone': plugin failed to load: ModuleNotFoundError"):
        make_effect("gone")
