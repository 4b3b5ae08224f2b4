"""A network trained by a ``tcbench run`` compensation job, kept as ``device.json``
(:mod:`tcbench.compensation.run_device`) and exported by ``tcbench export runs=[...] formats=[c]``:
compiled with the system C compiler and run sample by sample over the run's test record, it gives
the run's own compensation (the task's learner compensator) to 1e-9 (double build) and 1e-4 (float
build), relative to the larger of the output and the record's largest raw reading. The
full-temperature task's network (``msra_fulltemp``: ``[raw, T]`` to the input) runs too, and
returns the task's own estimate of the input in g to the same tolerances, relative to its largest.
So do a run's ``poly`` of every form and degree, its lag-aware polynomial (``learner=lagpoly``) and
its diagnosed model (``learner=model``)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import replace
from types import SimpleNamespace
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import tcbench  # noqa: F401 - registers the envs
from test_c_export import _stable
from tcbench.compensation import methods
from tcbench.compensation.c_export import c_sources, device_clock_s, run_model_spec, streamed_corrected, write_c
from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.compensation.run_device import BASELINE_FITS, device_document
from tcbench.runner.loop import compensate

CC = shutil.which("cc")
TOLERANCE = {"double": 1e-9, "float": 1e-4}
ENV = "tcbench/Accel-Chamber-v0"
FULLTEMP = "tcbench/MSRA-FullTemp-v0"
HOST = Path(__file__).with_name("test_c_export.py").read_text().split('HOST = r"""')[1].split('"""')[0]


def _trained(learner: str, params: dict) -> tuple[object, dict]:
    """The chamber task (one cycle to train, one to test) with ``learner`` trained as a run trains
    it, and the ``device.json`` the run keeps."""
    env = gym.make(ENV, learner=learner, learner_params=params, n_train=1, n_test=1, recordings_seed=0).unwrapped
    compensate(env, learner, "none", {}, 1, 0)
    return env, device_document(env, learner, f"random-{learner}")


@pytest.fixture(scope="module")
def trained() -> dict[str, tuple[object, dict]]:
    """Each network trained once (lazily: the Elman's 30 epochs take about 20 s)."""
    class Lazy(dict):
        def __missing__(self, learner: str) -> tuple[object, dict]:
            params = {"training": "gd", "epochs": 50} if learner == "bp" else {"epochs": 30}
            self[learner] = _trained(learner, params)
            return self[learner]

    return Lazy()


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
@pytest.mark.parametrize("build", ["double", "float"])
@pytest.mark.parametrize("learner", ["bp", pytest.param("elman", marks=pytest.mark.slow)])
def test_the_compiled_run_network_gives_the_runs_compensation(trained: dict, learner: str, build: str,
                                                               tmp_path: Path) -> None:
    env, doc = trained[learner]
    assert doc["sensor"] == "accel" and doc["unit"] == "g" and list(doc["device"]) == [learner]
    spec = json.loads(json.dumps(doc["device"][learner]))  # as the artifact holds it
    tr = env.data.test[0]
    rec = tr.recording
    t_s, temp_c, raw = rec.time_s, rec.temperature_c, rec.output
    dt_s = np.r_[0.0, np.diff(t_s)]
    got, stderr = _streamed_by_c(spec, f"tc_accel_{learner}", rec, build, tmp_path)
    assert "dropped 0" in stderr
    box = env.data.input_range(env._x)
    want = methods.learner_compensator(env.data, env.learner, box)(tr, raw)  # the run's own compensation
    bound = TOLERANCE[build] * np.maximum(np.abs(want), np.max(np.abs(raw)))
    keep = np.ones(raw.size, dtype=bool)
    if learner == "elman":  # up to where the reference's own rounding has grown to the tolerance
        clock = device_clock_s(dt_s)
        keep = _stable(spec, clock, temp_c, temperature_rate_c_per_s(clock, temp_c, spec["rate_window_s"]), bound,
                       build)
        assert np.mean(keep) > 0.9
    worst = int(np.argmax(np.where(keep, np.abs(got - want) / bound, 0.0)))
    assert np.all(np.abs(got - want)[keep] <= bound[keep]), (worst, got[worst], want[worst])
    assert np.ptp(want - raw) > 10 * TOLERANCE["float"] * np.max(np.abs(raw))  # the network corrects something


@pytest.fixture(scope="module")
def fulltemp() -> dict[str, tuple[object, dict]]:
    """The full-temperature task (one run to train, one to test) with each network trained once as
    a run trains it (few epochs), and the ``device.json`` the run keeps."""
    class Lazy(dict):
        def __missing__(self, learner: str) -> tuple[object, dict]:
            params = {"training": "gd", "epochs": 50} if learner == "bp" else {"epochs": 5}
            env = gym.make(FULLTEMP, learner=learner, learner_params=params, n_train=1, n_test=1,
                           recordings_seed=0).unwrapped
            compensate(env, learner, "none", {}, 1, 0)
            self[learner] = env, device_document(env, learner, f"random-{learner}")
            return self[learner]

    return Lazy()


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
@pytest.mark.parametrize("build", ["double", "float"])
@pytest.mark.parametrize("learner", ["bp", pytest.param("elman", marks=pytest.mark.slow)])
def test_the_compiled_fulltemp_network_estimates_the_input_as_the_task_does(fulltemp: dict, learner: str,
                                                                           build: str, tmp_path: Path) -> None:
    """msra_fulltemp's network maps [raw, T] to the input: ``tcbench export runs=[device.json]``
    writes it as C whose update returns the estimate in g, the temperature held to the training
    range (the test run goes below it), as the task compensates, to the tolerance in both builds."""
    env, doc = fulltemp[learner]
    assert doc["sensor"] == "msra" and doc["unit"] == "Hz" and "left_out" not in doc
    spec = doc["device"][learner]
    assert spec["form"] == "inverse" and spec["inputs"] == ["raw", "temperature_c"]
    assert (spec["input_quantity"], spec["input_unit"]) == ("acceleration", "g")
    kept = tmp_path / "0123456789abcdef" / "artifacts" / "device.json"  # where a run keeps it
    kept.parent.mkdir(parents=True)
    kept.write_text(json.dumps(doc, indent=1))
    done = _tcbench("export", f"runs=[{kept}]", "formats=[c]", "out=c", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    name = f"tc_msra_{learner}_01234567"
    header, source = ((tmp_path / "c" / f"{name}.{e}").read_text() for e in "hc")
    assert "estimate of the input (acceleration, in g)" in header and "not a corrected output" in header
    assert "RATE_CAPACITY" not in header and "alloc" not in source  # no rate window, no allocation
    (tmp_path / "c" / "host.c").write_text(HOST.replace("UPNAME", name.upper()).replace("NAME", name))
    exe = tmp_path / name
    flags = [f"-D{name.upper()}_FLOAT"] if build == "float" else []
    subprocess.run([CC, "-std=c99", "-O2", *flags, str(tmp_path / "c" / "host.c"), str(tmp_path / "c" / f"{name}.c"),
                    "-lm", "-o", str(exe)], check=True)
    tr = env.data.test[0]
    rec = tr.recording
    temp_c, raw = rec.temperature_c, rec.output
    dt_s = np.r_[0.0, np.diff(rec.time_s)]
    lines = "".join(f"{a.hex()} {b.hex()} {c.hex()}\n" for a, b, c in zip(temp_c.tolist(), raw.tolist(), dt_s.tolist()))
    done = subprocess.run([str(exe)], input=lines, capture_output=True, text=True, check=True)
    got = np.array([float.fromhex(v) for v in done.stdout.split()])
    box = env.data.input_range(env._x)
    want = methods.learner_compensator(env.data, env.learner, box)(tr, raw)  # the task's own compensation, g
    assert got.size == want.size
    bound = TOLERANCE[build] * np.max(np.abs(want))  # the estimate crosses 0 g: relative to its largest
    worst = int(np.argmax(np.abs(got - want)))
    assert np.all(np.abs(got - want) <= bound), (worst, got[worst], want[worst])
    below = temp_c < box[0][1]  # the clamp acts: the unclamped network differs there
    free = env.learner.predict(np.column_stack([raw, temp_c]))
    assert below.any() and np.max(np.abs(free - want)[below]) > 5 * bound
    if learner == "bp":  # the network estimates the input (better than a constant 0 g)
        assert np.sqrt(np.mean((want - rec.input) ** 2)) < np.sqrt(np.mean(rec.input ** 2))


def _streamed_by_c(spec: dict, name: str, rec: object, build: str, folder: Path) -> tuple[np.ndarray, str]:
    """``spec`` written as C, compiled in ``build`` and run sample by sample over ``rec``: its
    outputs, and what the host program printed on stderr."""
    write_c(spec, name, folder)
    (folder / "host.c").write_text(HOST.replace("UPNAME", name.upper()).replace("NAME", name))
    exe = folder / name
    flags = [f"-D{name.upper()}_FLOAT"] if build == "float" else []
    subprocess.run([CC, "-std=c99", "-O2", *flags, str(folder / "host.c"), str(folder / f"{name}.c"), "-lm",
                    "-o", str(exe)], check=True)
    dt_s = np.r_[0.0, np.diff(rec.time_s)]
    lines = "".join(f"{a.hex()} {b.hex()} {c.hex()}\n"
                    for a, b, c in zip(rec.temperature_c.tolist(), rec.output.tolist(), dt_s.tolist()))
    done = subprocess.run([str(exe)], input=lines, capture_output=True, text=True, check=True)
    return np.array([float.fromhex(v) for v in done.stdout.split()]), done.stderr


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
@pytest.mark.parametrize("build", ["double", "float"])
@pytest.mark.parametrize(("task", "offsets"), [(ENV, "shared"), (ENV, "per_run"), ("tcbench/MSRA-ZeroBias-v0", "per_run")])
def test_a_runs_cubic_runs_on_the_device_as_the_task_compensates(task: str, offsets: str, build: str,
                                                                  tmp_path: Path) -> None:
    """A run's poly learner (the boards' poly3 and poly3_runs: a Chebyshev series in the scaled
    temperature) is kept as the device's cubic about the middle of the training range, held to it:
    compiled, it gives the task's own compensation in both builds."""
    env = gym.make(task, learner="poly", learner_params={"offsets": offsets}, n_train=2, n_test=1,
                   recordings_seed=0).unwrapped
    compensate(env, "poly", "none", {}, 1, 0)
    doc = device_document(env, "poly", "poly3")
    spec = json.loads(json.dumps(doc["device"]["poly"]))
    box = env.data.input_range(env._x)
    assert spec["method"] == "poly3" and (spec["tmin_c"], spec["tmax_c"]) == (box[0][0], box[1][0])
    test = env.data.test[0]
    data = test.recording.data.copy()
    data["temperature_c"] += box[1][0] - np.median(data["temperature_c"])  # half the record above the training range
    warmer = replace(test, recording=replace(test.recording, data=data))
    for tr in (test, warmer):
        raw = tr.recording.output
        got, _ = _streamed_by_c(spec, "tc_poly", tr.recording, build, tmp_path)
        want = methods.learner_compensator(env.data, env.learner, box)(tr, raw)
        bound = TOLERANCE[build] * np.maximum(np.abs(want), np.max(np.abs(raw)))
        assert np.all(np.abs(got - want) <= bound), np.max(np.abs(got - want) / bound)
        assert np.ptp(want - raw) > 10 * TOLERANCE["float"] * np.max(np.abs(raw))  # the cubic corrects something
    assert np.any(warmer.recording.temperature_c > box[1][0])  # the clamp is exercised


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
@pytest.mark.parametrize("build", ["double", "float"])
@pytest.mark.parametrize(("task", "learner_params", "method"), [
    (ENV, {"form": "bias_rate"}, "poly_rate"),
    ("tcbench/MSRA-ZeroBias-v0", {"form": "bias_rate", "degree": 4, "offsets": "per_run"}, "poly_rate"),
    (FULLTEMP, {}, "poly"),
    (ENV, {"degree": 5}, "poly"),
])
def test_a_runs_poly_of_every_form_and_degree_runs_on_the_device(task: str, learner_params: dict, method: str,
                                                                 build: str, tmp_path: Path) -> None:
    """A run's poly learner other than the cubic PX4 runs (the rate term a polynomial in T on the
    device's trailing rate window, the input solved from [raw, T], a degree above 3) is kept as its
    Chebyshev series in the scaled inputs: compiled, it gives the task's own compensation (the
    estimate in g for fulltemp) in both builds, its inputs held to the training box."""
    n_train = 1 if task == FULLTEMP else 2  # fulltemp's test run then goes below the training range
    env = gym.make(task, learner="poly", learner_params=learner_params, n_train=n_train, n_test=1,
                   recordings_seed=0).unwrapped
    compensate(env, "poly", "none", {}, 1, 0)
    doc = device_document(env, "poly", "poly")
    assert "left_out" not in doc
    spec = json.loads(json.dumps(doc["device"]["poly"]))
    assert spec["method"] == method and spec["degree"] == learner_params.get("degree", 3)
    box = env.data.input_range(env._x)
    tr = env.data.test[0]
    raw = tr.recording.output
    got, stderr = _streamed_by_c(spec, "tc_poly", tr.recording, build, tmp_path)
    want = methods.learner_compensator(env.data, env.learner, box)(tr, raw)
    inverse = spec["form"] == "inverse"
    bound = TOLERANCE[build] * (np.max(np.abs(want)) if inverse else np.maximum(np.abs(want), np.max(np.abs(raw))))
    assert got.size == want.size and np.all(np.abs(got - want) <= bound), np.max(np.abs(got - want) / bound)
    header = c_sources(spec, "tc_poly").header
    if inverse:  # the polynomial's estimate of the input in g, the temperature held to its range
        assert "polynomial's estimate of the input (acceleration, in g)" in header
        temp_c = tr.recording.temperature_c
        free = env.learner.predict(np.column_stack([raw, temp_c]))
        below = temp_c < box[0][1]
        assert below.any() and np.max(np.abs(free - want)[below]) > 1e3 * TOLERANCE["double"] * np.max(np.abs(want))
        assert np.sqrt(np.mean((want - tr.recording.input) ** 2)) < np.sqrt(np.mean(tr.recording.input ** 2))
    else:
        assert np.ptp(want - raw) > 10 * TOLERANCE["float"] * np.max(np.abs(raw))  # it corrects something
    if method == "poly_rate":  # the rate term acts: without it the output differs
        assert "dropped 0" in stderr and "RATE_CAPACITY" in header
        flat = spec | {"rate": [0.0] * len(spec["rate"])}
        clock = device_clock_s(np.r_[0.0, np.diff(tr.recording.time_s)])
        without = streamed_corrected(flat, clock, tr.recording.temperature_c, raw)
        assert np.max(np.abs(without - want)) > 1e4 * TOLERANCE["double"] * np.max(np.abs(raw))


def _baseline(task: str, learner: str, n_train: int) -> tuple[object, dict, object]:
    """``task`` with the baseline ``learner`` scored as a run scores it, the ``device.json`` the
    run keeps (:func:`~tcbench.runner.kinds.compensation.CompensationKind.record` passes the fit its
    score keeps), and that fit."""
    env = gym.make(task, learner=None, n_train=n_train, n_test=1, recordings_seed=0).unwrapped
    result = compensate(env, learner, "none", {}, 1, 0)
    key = BASELINE_FITS[learner]
    fitted = result.score.extra.get(key) if key else None
    return env, device_document(env, learner, learner, fitted), fitted


def _compiled_agrees(spec: dict, env: object, want: np.ndarray, build: str, folder: Path, inverse: bool) -> None:
    """``spec``'s C over the task's test record gives ``want`` to the build's tolerance."""
    rec = env.data.test[0].recording
    got, _ = _streamed_by_c(spec, "tc_run", rec, build, folder)
    bound = TOLERANCE[build] * (np.max(np.abs(want)) if inverse else np.maximum(np.abs(want), np.max(np.abs(rec.output))))
    assert got.size == want.size and np.all(np.abs(got - want) <= bound), np.max(np.abs(got - want) / bound)


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
@pytest.mark.parametrize("build", ["double", "float"])
@pytest.mark.parametrize("task", [ENV, "tcbench/MSRA-ZeroBias-v0", FULLTEMP])
def test_a_runs_lagpoly_runs_on_the_device_as_the_task_compensates(task: str, build: str, tmp_path: Path) -> None:
    """learner=lagpoly: its lag the model's streaming first-order filter, its polynomial in the
    lagged temperature; compiled, it gives the task's own compensation in both builds (fulltemp:
    the input solved from the reading, in g, as the header says)."""
    env, doc, fitted = _baseline(task, "lagpoly", 2)
    spec = json.loads(json.dumps(doc["device"]["lagpoly"]))
    assert spec["method"] == "lagpoly" and spec["effects"] == [{"id": "thermal_lag", "tau_s": fitted.tau_s}]
    tr = env.data.test[0]
    want = methods.lagpoly_compensator(env.data, fitted)(tr, tr.recording.output)
    inverse = task == FULLTEMP
    _compiled_agrees(spec, env, want, build, tmp_path, inverse)
    assert ("the acceleration, in g, not a corrected output" in c_sources(spec, "x").header) == inverse
    unlagged = spec | {"effects": []}  # the lag acts: without it the output differs
    clock = device_clock_s(np.r_[0.0, np.diff(tr.recording.time_s)])
    without = streamed_corrected(unlagged, clock, tr.recording.temperature_c, tr.recording.output)
    assert np.max(np.abs(without - want)) > 1e4 * TOLERANCE["double"] * np.max(np.abs(want))


@pytest.mark.slow
@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
def test_a_runs_diagnosed_model_runs_on_the_device_as_the_task_compensates(tmp_path: Path) -> None:
    """learner=model on the room-temperature task: one model diagnosed per training run (here one
    with a thermal lag, one without), the mean of their offsets removed; the device runs each on its
    own state (``model_mean``) and, compiled, gives the task's own compensation in both builds (the
    models hold only terms the device runs as the task's grid does: the lag and the polynomial)."""
    env, doc, fitted = _baseline("tcbench/MSRA-ZeroBias-v0", "model", 2)
    spec = json.loads(json.dumps(doc["device"]["model"]))
    assert spec["method"] == "model_mean" and len(spec["models"]) == 2
    assert any(m["effects"] for m in spec["models"])
    tr = env.data.test[0]
    rec = tr.recording
    want = rec.output - fitted.bias(rec.time_s, rec.temperature_c)  # the task's compensator
    for build in ("double", "float"):
        _compiled_agrees(spec, env, want, build, tmp_path, False)
    one = streamed_corrected(spec["models"][0], device_clock_s(np.r_[0.0, np.diff(rec.time_s)]), rec.temperature_c,
                             rec.output)
    assert np.max(np.abs(one - want)) > 1e4 * TOLERANCE["double"] * np.max(np.abs(rec.output))  # the mean acts


GYRO = ("tcbench/Gyro-DriftNoise-v0", {"sample_rate_hz": 1.0, "hold_s": 600.0})  # a cheap gyro task


def test_what_no_device_runs_says_why() -> None:
    """The memoriser (a replay of the training runs, not a model) and the gyro task's pipeline
    (it decomposes the whole record) keep why no device runs them."""
    _, doc, _ = _baseline(ENV, "memoriser", 1)
    assert doc["device"] == {} and doc["left_out"]["memoriser"].startswith("a replay of the training runs' mean")
    env = gym.make(GYRO[0], learner="bp", learner_params={"training": "gd", "epochs": 2}, **GYRO[1]).unwrapped
    compensate(env, "bp", "none", {}, 1, 0)
    doc = device_document(env, "bp", "bp")
    assert doc["device"] == {} and doc["left_out"]["bp"].startswith("the task's pipeline decomposes the whole record")


def _tcbench(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = os.environ | {"MLFLOW_TRACKING_URI": f"sqlite:///{cwd / 'mlflow.db'}",
                        "PYTHONPATH": str(Path(tcbench.__file__).parents[1])}
    return subprocess.run([sys.executable, "-m", "tcbench", *args], cwd=cwd, env=env, capture_output=True, text=True)


@pytest.mark.slow
def test_export_takes_a_runs_id_and_refuses_in_one_line(tmp_path: Path) -> None:
    """``tcbench run`` keeps device.json; ``tcbench export runs=[ID] formats=[c]`` writes its C; an
    unknown id, a run without a network, an autopilot format: one line each, exit 2."""
    done = _tcbench("run", "task=accel_chamber", "task.n_train=1", "task.n_test=1", "task.recordings_seed=0",
                    "learner=bp", "learner.epochs=20", "optimiser=none", "budget=1", "seed=0", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    found = list((tmp_path / "mlartifacts").rglob("device.json"))
    assert len(found) == 1
    run_id = found[0].parent.parent.name
    done = _tcbench("export", f"runs=[{run_id}]", "formats=[c]", "out=c", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert {p.name for p in (tmp_path / "c").iterdir()} == {f"tc_accel_bp_{run_id[:8]}.{e}" for e in "ch"}
    assert f"tcbench run {run_id} on accel_chamber" in (tmp_path / "c" / f"tc_accel_bp_{run_id[:8]}.h").read_text()
    for args, says in ((["runs=[0123abcd]", "formats=[c]"], "runs: 0123abcd: no such run in"),
                       ([f"runs=[{run_id}]"], "runs: a run's network is written as C only (formats=[c])")):
        done = _tcbench("export", *args, "out=d", cwd=tmp_path)
        assert done.returncode == 2 and done.stderr.strip().splitlines() == [f"tcbench: error: {done.stderr.split('error: ')[1].strip()}"]
        assert says in done.stderr, done.stderr
    done = _tcbench("run", "task=accel_chamber", "task.n_train=1", "task.n_test=1", "task.recordings_seed=0",
                    "learner=raw", "seed=0", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    raw_id = [p.name for p in (tmp_path / "mlartifacts" / "tcbench").iterdir() if p.name != run_id][0]
    done = _tcbench("export", f"runs=[{raw_id}]", "formats=[c]", "out=e", cwd=tmp_path)
    assert done.returncode == 2 and "the run kept no device.json" in done.stderr, done.stderr


@pytest.mark.slow
def test_a_baselines_run_keeps_its_model_for_the_device(tmp_path: Path) -> None:
    """``tcbench run learner=lagpoly`` keeps device.json from its score's fit, which ``tcbench
    export runs=[ID] formats=[c]`` writes as C; a memoriser's run keeps why no device runs it, and
    the export says so in one line, exit 2."""
    ids = {}
    for learner in ("lagpoly", "memoriser"):
        before = set((tmp_path / "mlartifacts").rglob("device.json"))
        done = _tcbench("run", "task=msra_zerobias", "task.n_train=2", "task.n_test=1", "task.recordings_seed=0",
                        f"learner={learner}", "seed=0", cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        found = set((tmp_path / "mlartifacts").rglob("device.json")) - before
        assert len(found) == 1
        ids[learner] = found.pop().parent.parent.name
    done = _tcbench("export", f"runs=[{ids['lagpoly']}]", "formats=[c]", "out=c", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    header = (tmp_path / "c" / f"tc_msra_lagpoly_{ids['lagpoly'][:8]}.h").read_text()
    assert "by the lagpoly method" in header and f"the lagpoly model of tcbench run {ids['lagpoly']}" in header
    done = _tcbench("export", f"runs=[{ids['memoriser']}]", "formats=[c]", "out=d", cwd=tmp_path)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "no model a device runs (memoriser: a replay of the training runs" in done.stderr, done.stderr


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on this machine")
@pytest.mark.parametrize("build", ["double", "float"])
def test_the_mean_of_diagnosed_models_solves_for_the_input_as_the_task_does(build: str, tmp_path: Path) -> None:
    """learner=model of the full-temperature form: the task solves ``b + s a = U`` for the input
    with the models' mean ``b`` and ``s`` (:func:`~tcbench.tasks.diagnosed.solve_input`, no
    ``k a^2``); the device's ``model_mean`` returns ``(raw - mean b) / mean s`` in g, to the
    tolerance on a 1-Hz record through a temperature cycle at four input levels. A model with an
    ``accel_nonlinearity`` is left out with its reason."""
    from tcbench.sensors.effects import EFFECTS
    from tcbench.sensors.fitted import PolynomialModel as SensorModel
    from tcbench.tasks.diagnosed import DiagnosedModels, solve_input

    lag = EFFECTS["thermal_lag"]
    models = (SensorModel(sensor="msra", centre_c=20.0, half_range_c=50.0, bias=(138.4, -9.1, 0.01),
                          scale_factor=(199.3, 6.0, -0.001), effects=(lag(tau_s=300.0),)),
              SensorModel(sensor="msra", centre_c=15.0, half_range_c=45.0, bias=(138.2, -9.0), scale_factor=(199.0, 6.1)))
    fitted = DiagnosedModels(("a", "b"), models, ())
    t_s = np.arange(0.0, 7200.0)
    temp_c = 20.0 + 40.0 * np.sin(2 * np.pi * t_s / 7200.0)
    applied = np.repeat([1.0, 0.0, -1.0, 0.0], t_s.size // 4)
    b, s, k = fitted.response(t_s, temp_c)
    raw = b + s * applied + 0.01 * np.sin(t_s / 7.0)  # the mean model's reading, and a wiggle
    want = solve_input(raw, b, s, k)
    spec = json.loads(json.dumps(run_model_spec(fitted.models, True, "acceleration", "g")))
    assert spec["method"] == "model_mean" and spec["input_unit"] == "g"
    assert "It is the acceleration, in g, not a corrected output." in c_sources(spec, "x").header
    rec = SimpleNamespace(time_s=t_s, temperature_c=temp_c, output=raw)
    got, _ = _streamed_by_c(spec, "tc_mean", rec, build, tmp_path)
    bound = TOLERANCE[build] * np.max(np.abs(want))
    assert np.all(np.abs(got - want) <= bound), np.max(np.abs(got - want)) / bound
    assert np.max(np.abs(want - applied)) < 1e-3  # the mean model explains the reading
    k2 = (SensorModel(sensor="msra", bias=(138.0,), scale_factor=(199.0,),
                      effects=(EFFECTS["accel_nonlinearity"](k2_per_g2=0.1),)),)
    with pytest.raises(ValueError, match="its accel_nonlinearity term is not exported"):
        run_model_spec(k2, True)
