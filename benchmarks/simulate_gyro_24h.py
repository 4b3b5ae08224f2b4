"""Time and peak memory of simulating a 24 h gyro recording at 100 Hz (8.64 M samples).

The goal (project issue): a 24 h gyro recording at 100 Hz simulated in under 10 s with under
2 GB peak memory. The figure for the goal is the full, end-to-end call

    simulate_recording("gyro", "static", device_seed=0, seed=0, duration_s=86400, sample_rate_hz=100)

which builds the static profile, runs gyro 0's model (thermal lag, cubic and rate terms, white
noise, the flicker bank, quantisation), draws the thermometer and returns the validated
:class:`~tcbench.sensors.recording.Recording`. It is split into

- ``model``: ``unit("gyro", 0).model.simulate(gyro_static(86400, sample_rate_hz=100), rng)``
  (device, profile and model output);
- ``recording``: the rest of ``simulate_recording`` (thermometer draw and quantisation,
  ``make_recording`` with its validation), timed on a profile and output made beforehand; the
  code mirrors ``simulate_recording``'s tail, with the sidecar's ``extra`` cut to the draws.

No other library simulates a MEMS gyro recording, so there is no peer for the goal figure. The
like-for-like peer comparison is of the noise generators, on the same length and sample rate:
tcbench's ``noise.white`` and ``noise.flicker`` (Gauss-Markov bank) against allantools'
``noise.white``, its Kasdin power-law generator ``Noise(nr, qd, b=-1)`` (1/f series, at the
record length and at the power-of-two length its docstring asks for, then truncated) and its
``noise.pink`` (Voss-McCartney by name; a pure-Python per-sample generator). Amplitudes are
gyro 0's: white density N (deg/s per sqrt(Hz); allantools ``b0 = 2 N^2``, the same per-sample
sigma) and bias instability B (Allan floor 0.664 B; Kasdin ``qd = B^2`` gives the 1/f level
``h_-1 = qd / pi = B^2 / pi`` whose floor is 0.664 B). Each generator's last output is checked
with tcbench's Allan deviation (slope between tau = 1 s and 100 s: -0.5 white, 0 flicker).

How it measures. Every row runs in a fresh child process (this script re-run with a hidden
``--child`` flag, same interpreter), one row at a time, so rows neither share caches nor
inherit each other's memory. In the child, after all imports:

- wall time: ``time.perf_counter`` around each of ``--repeats`` calls (each result is dropped
  before the next call); the table gives the best, and the first call of the fresh process;
- peak RSS: ``resource.getrusage(RUSAGE_SELF).ru_maxrss`` (KiB on Linux) after the calls,
  total and minus the child's value after its imports (the baseline). For ``recording`` the
  setup (a full model run) would mask the peak, so the child resets its high-water mark
  (``/proc/self/clear_refs``) after the setup and the baseline is the RSS at that point;
- tracemalloc peak of one call, in a second child (tracing slows numpy's small calls), which
  counts numpy's buffers but not the interpreter or shared libraries.

Linux caveat: ru_maxrss of a child starts at its parent's high-water mark (exec keeps it), so
this parent never allocates record-sized arrays; each child also reports /proc's VmHWM,
which is not inherited, as a cross-check. The targets are judged on the best time and on the
child's total peak RSS (interpreter and imports included) against 2 GiB = 2048 MiB.

Usage::

    python benchmarks/simulate_gyro_24h.py --repeats 3 --hours 24 --rate-hz 100
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import allantools
import numpy as np
from common import (
    add_json,
    command_line,
    parser_for,
    peak_mib,
    print_heading,
    table_head,
    table_row,
    versions,
    write_json,
)

from tcbench.sensors import noise
from tcbench.sensors.kinds import profile_input, unit
from tcbench.sensors.protocols import gyro_static
from tcbench.sensors.recording import make_recording
from tcbench.sensors.simulate import (
    THERMOMETER_NOISE_C,
    THERMOMETER_STEP_C,
    simulate_recording,
)
from tcbench.signal.allan import BIAS_INSTABILITY_FACTOR, allan_deviation

TIME_LIMIT_S = 10.0  # the goal: under 10 s ...
MEMORY_LIMIT_MIB = 2048.0  # ... and under 2 GiB peak memory
PEAK_PER_RECORDING = 2.0  # ... and a traced peak at most twice the recording it returns
DEVICE_SEED = 0
RUN_SEED = 0
CHECK_TAUS_S = (1.0, 100.0)  # Allan check of the generators' outputs (shorter for short records)
DEFAULT_JSON = Path(__file__).with_name("simulate_gyro_24h.json")
EXPECTED_SLOPE = {"white": -0.5, "flicker": 0.0}  # log-log Allan slope of each kind of noise


@dataclass(frozen=True)
class Config:
    """Record length and sample rate."""

    hours: float
    rate_hz: float

    @property
    def duration_s(self) -> float:
        return self.hours * 3600.0

    @property
    def n(self) -> int:
        """Samples in the record: the length of ``gyro_static``'s ``np.arange(0, T, 1 / fs)``,
        computed as numpy does (``ceil(T / step)``) without allocating it."""
        return math.ceil(self.duration_s / (1.0 / self.rate_hz))

    @property
    def dt_s(self) -> float:
        return 1.0 / self.rate_hz

    @property
    def check_taus_s(self) -> tuple[float, float]:
        """The Allan-check taus, the longer one capped at a tenth of the record."""
        return CHECK_TAUS_S[0], min(CHECK_TAUS_S[1], self.duration_s / 10.0)


@dataclass(frozen=True)
class Task:
    """One measured row: ``run(cfg, state)`` is timed, ``setup(cfg)`` (if any) is not.

    ``kind``: ``white`` or ``flicker`` for a noise generator (its output gets the Allan check),
    ``""`` otherwise.
    """

    label: str
    group: str  # "goal", "split" or "peer"
    library: str
    run: Callable[[Config, Any], Any]
    setup: Callable[[Config], Any] | None = None
    kind: str = ""


# --- what is measured -----------------------------------------------------------------------


def gyro_noise_levels() -> tuple[float, float]:
    """Gyro 0's white-noise density N (deg/s per sqrt(Hz)) and bias instability B (deg/s)."""
    model = unit("gyro", DEVICE_SEED).model
    return model.effect("white_noise").density, model.effect("bias_instability").b  # type: ignore[union-attr]


def sensor_rng() -> np.random.Generator:
    """The model's stream in ``simulate_recording`` (second child of the run seed)."""
    return np.random.default_rng(np.random.SeedSequence(RUN_SEED).spawn(3)[1])


def run_full(cfg: Config, _: Any) -> Any:
    return simulate_recording(
        "gyro", "static", device_seed=DEVICE_SEED, seed=RUN_SEED,
        duration_s=cfg.duration_s, sample_rate_hz=cfg.rate_hz,
    )


def run_model(cfg: Config, _: Any) -> Any:
    profile = gyro_static(cfg.duration_s, sample_rate_hz=cfg.rate_hz)
    return unit("gyro", DEVICE_SEED).model.simulate(profile, sensor_rng())


def setup_recording(cfg: Config) -> tuple[Any, np.ndarray]:
    profile = gyro_static(cfg.duration_s, sample_rate_hz=cfg.rate_hz)
    return profile, unit("gyro", DEVICE_SEED).model.simulate(profile, sensor_rng())


def run_recording(cfg: Config, state: tuple[Any, np.ndarray]) -> Any:
    """The tail of ``simulate_recording``: thermometer reading, then the validated Recording."""
    profile, output = state
    rng = np.random.default_rng(np.random.SeedSequence(RUN_SEED).spawn(3)[2])
    reading = rng.standard_normal(profile.t_s.size)
    reading *= THERMOMETER_NOISE_C
    reading += profile.temp_c
    device = unit("gyro", DEVICE_SEED)
    return make_recording(
        profile.t_s, noise.quantise(reading, THERMOMETER_STEP_C, in_place=True), profile_input(profile), output,
        sensor="gyro", sample_rate_hz=profile.sample_rate_hz, device_id=device.device_id,
        position=profile.position, extra={"device_draws": device.draws},
    )


def run_tc_white(cfg: Config, _: Any) -> np.ndarray:
    density, _b = gyro_noise_levels()
    return noise.white(cfg.n, density * np.sqrt(cfg.rate_hz), np.random.default_rng(RUN_SEED))


def run_at_white(cfg: Config, _: Any) -> np.ndarray:
    density, _b = gyro_noise_levels()
    np.random.seed(RUN_SEED)
    return allantools.noise.white(cfg.n, b0=2.0 * density**2, fs=cfg.rate_hz)


def run_tc_flicker(cfg: Config, _: Any) -> np.ndarray:
    _n, b = gyro_noise_levels()
    return noise.flicker(cfg.n, cfg.dt_s, b, np.random.default_rng(RUN_SEED))


def kasdin(nr: int, n: int) -> np.ndarray:
    """allantools' Kasdin generator, 1/f series of length ``nr``, first ``n`` samples."""
    _n, b = gyro_noise_levels()
    np.random.seed(RUN_SEED)
    gen = allantools.Noise(nr=nr, qd=b * b, b=-1)
    gen.generateNoise()
    return gen.time_series[:n]


def next_pow2(n: int) -> int:
    return 1 << (n - 1).bit_length()


def run_at_kasdin(cfg: Config, _: Any) -> np.ndarray:
    return kasdin(cfg.n, cfg.n)


def run_at_kasdin_pow2(cfg: Config, _: Any) -> np.ndarray:
    return kasdin(next_pow2(cfg.n), cfg.n)


def run_at_pink(cfg: Config, _: Any) -> np.ndarray:
    np.random.seed(RUN_SEED)
    return allantools.noise.pink(cfg.n)


TASKS: dict[str, Task] = {
    "full": Task("`simulate_recording` end to end", "goal", "tcbench", run_full),
    "model": Task("profile + `model.simulate`", "split", "tcbench", run_model),
    "recording": Task("thermometer + `make_recording` (validation)", "split", "tcbench",
                      run_recording, setup=setup_recording),
    "tc_white": Task("`noise.white`", "peer", "tcbench", run_tc_white, kind="white"),
    "at_white": Task("`noise.white`", "peer", "allantools", run_at_white, kind="white"),
    "tc_flicker": Task("`noise.flicker` (Gauss-Markov bank)", "peer", "tcbench", run_tc_flicker,
                       kind="flicker"),
    "at_kasdin": Task("`Noise(b=-1)` Kasdin, nr = record length", "peer", "allantools",
                      run_at_kasdin, kind="flicker"),
    "at_kasdin_pow2": Task("`Noise(b=-1)` Kasdin, nr = next power of 2, truncated", "peer",
                           "allantools", run_at_kasdin_pow2, kind="flicker"),
    "at_pink": Task("`noise.pink` (Voss-McCartney, per-sample Python)", "peer", "allantools",
                    run_at_pink, kind="flicker"),
}
PEER_PAIRS = {"at_white": "tc_white", "at_kasdin": "tc_flicker", "at_kasdin_pow2": "tc_flicker",
              "at_pink": "tc_flicker"}


# --- child side -----------------------------------------------------------------------------


def maxrss_mib() -> float:
    """Peak resident set size of this process so far, MiB (ru_maxrss is KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def proc_status_mib(field: str) -> float | None:
    """A ``/proc/self/status`` memory field (``VmRSS``, ``VmHWM``) in MiB, None off Linux."""
    try:
        text = Path("/proc/self/status").read_text()
    except OSError:
        return None
    match = re.search(rf"^{field}:\s+(\d+) kB", text, re.MULTILINE)
    return int(match.group(1)) / 1024.0 if match else None


def reset_peak_rss() -> bool:
    """Reset this process's RSS high-water mark to its current RSS (Linux >= 4.0)."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        return False
    return True


def allan_check(x: np.ndarray, cfg: Config, kind: str) -> dict[str, float]:
    """Allan deviation of a generator's output at ``cfg.check_taus_s``, its log-log slope, and
    the ratio to the expected level (white: N / sqrt(tau); flicker: 0.664 B)."""
    density, b = gyro_noise_levels()
    taus = cfg.check_taus_s
    adev = allan_deviation(np.asarray(x, dtype=np.float64), cfg.rate_hz, np.array(taus)).adev
    (t1, t2), (a1, a2) = taus, adev
    expected = (
        [density / np.sqrt(t) for t in taus] if kind == "white"
        else [BIAS_INSTABILITY_FACTOR * b] * 2
    )
    return {
        "adev_tau1": float(a1), "adev_tau2": float(a2),
        "slope": float(np.log(a2 / a1) / np.log(t2 / t1)),
        "ratio_tau1": float(a1 / expected[0]), "ratio_tau2": float(a2 / expected[1]),
    }


def measure_time(task: Task, cfg: Config, repeats: int) -> dict[str, Any]:
    """Wall times of ``repeats`` calls and the peak RSS around them, in this (fresh) process;
    then the Allan check of the last output (after the peak is read)."""
    baseline, baseline_hwm = maxrss_mib(), proc_status_mib("VmHWM")
    state = task.setup(cfg) if task.setup else None
    reset = False
    if task.setup:
        reset = reset_peak_rss()
        baseline = maxrss_mib() if reset else float("nan")
    times, out = [], None
    for _ in range(repeats):
        del out  # drop the previous result before the next call
        t0 = time.perf_counter()
        out = task.run(cfg, state)
        times.append(time.perf_counter() - t0)
    peak, peak_hwm = maxrss_mib(), proc_status_mib("VmHWM")
    return {
        "times_s": times, "best_s": min(times), "first_s": times[0],
        "baseline_mib": baseline, "peak_rss_mib": peak, "peak_above_baseline_mib": peak - baseline,
        "baseline_vmhwm_mib": baseline_hwm, "peak_vmhwm_mib": peak_hwm, "hwm_reset": reset,
        "allan": allan_check(out, cfg, task.kind) if task.kind else {},
    }


def result_mib(out: Any) -> float:
    """Memory the returned object owns, MiB: a recording's table columns, or an array."""
    if isinstance(out, np.ndarray):
        return out.nbytes / 2**20
    return sum(out.data[c].to_numpy().nbytes for c in out.data.columns) / 2**20


def measure_trace(task: Task, cfg: Config) -> dict[str, Any]:
    """tracemalloc peak of one call (setup not traced) and the size of what it returns, MiB."""
    state = task.setup(cfg) if task.setup else None
    returned: list[Any] = []
    peak = peak_mib(lambda: returned.append(task.run(cfg, state)))
    return {"tracemalloc_peak_mib": peak, "returned_mib": result_mib(returned[0])}


# --- parent side ----------------------------------------------------------------------------


def in_child(name: str, mode: str, args: argparse.Namespace) -> dict[str, Any]:
    """Run one measurement in a fresh interpreter (this script, ``--child``) and parse its JSON."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", name, "--mode", mode,
           "--repeats", str(args.repeats), "--hours", str(args.hours), "--rate-hz", str(args.rate_hz)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"child {name}/{mode} failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def verdict(ok: bool) -> str:
    return "pass" if ok else "**FAIL**"


def fmt(x: float | None, spec: str) -> str:
    return "n/a" if x is None or x != x else format(x, spec)


def report(rows: dict[str, dict[str, Any]], cfg: Config, args: argparse.Namespace,
           libraries: dict[str, str], load: tuple[float, float]) -> None:
    """Print the markdown report."""
    hours = f"{args.hours:g} h at {args.rate_hz:g} Hz"
    print_heading(f"Simulating a {hours} gyro recording ({cfg.n} samples)", command_line(),
                  libraries)
    print(f"1-min load average at start / end: {load[0]:.1f} / {load[1]:.1f} (other jobs on the "
          "machine inflate wall times; best-of-N only partly hides that).\n")
    print(f"Each row in a fresh child process; best of {args.repeats} calls and the first call; "
          "peak RSS from ru_maxrss (total, and above the child's RSS after imports); tracemalloc "
          "peak of one call in a separate child.\n")
    print("\n".join(table_head(
        ["thing measured", "samples", "best wall time (s)", "first call (s)", "peak RSS (MiB)",
         "peak RSS above baseline (MiB)", "tracemalloc peak (MiB)", "returned (MiB)",
         "tracemalloc peak / returned", "< 10 s", "< 2 GiB", "peak <= 2x recording"],
        "lrrrrrrrrlll",
    )))
    for name, r in rows.items():
        task = TASKS[name]
        if task.group == "peer":
            continue
        goal = task.group == "goal"
        print(table_row([
            task.label, r["samples"], f"{r['best_s']:.3f}", f"{r['first_s']:.3f}",
            fmt(r["peak_rss_mib"], ".0f") if goal else "-",
            fmt(r["peak_above_baseline_mib"], ".0f"), f"{r['tracemalloc_peak_mib']:.0f}",
            f"{r['returned_mib']:.0f}", f"{r['tracemalloc_peak_mib'] / r['returned_mib']:.2f}",
            verdict(r["best_s"] < TIME_LIMIT_S) if goal else "",
            verdict(r["peak_rss_mib"] < MEMORY_LIMIT_MIB) if goal else "",
            verdict(r["tracemalloc_peak_mib"] <= PEAK_PER_RECORDING * r["returned_mib"]) if goal else "",
        ]))
    full, model, rec = rows["full"], rows["model"], rows["recording"]
    print(f"\nGoal figure: the first row. Targets judged on the best time and on the *total* "
          f"peak RSS of the child (interpreter and imports included, "
          f"{full['baseline_mib']:.0f} MiB after imports). Split: model "
          f"{model['best_s']:.2f} s + recording {rec['best_s']:.2f} s = "
          f"{model['best_s'] + rec['best_s']:.2f} s against {full['best_s']:.2f} s end to end.")
    hwm = [r for r in rows.values() if r["baseline_vmhwm_mib"] is not None and not r["hwm_reset"]]
    drift = max((max(abs(r["baseline_mib"] - r["baseline_vmhwm_mib"]),
                     abs(r["peak_rss_mib"] - r["peak_vmhwm_mib"])) for r in hwm), default=float("nan"))
    print(f"Cross-check: ru_maxrss and /proc VmHWM (not inherited) differ by at most {drift:.1f} MiB "
          "at the baselines and peaks of the children.\n")

    print("Noise generators, like for like (same length, sample rate and gyro 0's amplitudes); "
          "ratio = allantools time / tcbench time for the same kind of noise.\n")
    tau1, tau2 = cfg.check_taus_s
    print("\n".join(table_head(
        ["library", "generator", "samples", "best wall time (s)", "ns / sample",
         "ratio allantools/tcbench", "peak RSS above baseline (MiB)", "tracemalloc peak (MiB)",
         f"Allan slope {tau1:g}-{tau2:g} s (expected)",
         f"adev / expected at {tau1:g} s, {tau2:g} s"],
        "llrrrrrrrl",
    )))
    for name, r in rows.items():
        task = TASKS[name]
        if task.group != "peer":
            continue
        ref = PEER_PAIRS.get(name)
        ratio = f"{r['best_s'] / rows[ref]['best_s']:.2f}x" if ref else "-"
        a = r["allan"]
        print(table_row([
            task.library, task.label, r["samples"], f"{r['best_s']:.3f}",
            f"{1e9 * r['best_s'] / r['samples']:.1f}", ratio,
            f"{r['peak_above_baseline_mib']:.0f}", f"{r['tracemalloc_peak_mib']:.0f}",
            f"{a['slope']:+.2f} ({EXPECTED_SLOPE[task.kind]:+.1f})",
            f"{a['ratio_tau1']:.2f}, {a['ratio_tau2']:.2f}",
        ]))
    print(f"\nThe goal figure is the full simulation above; the generator rows are the peer "
          f"comparison (no peer library simulates a gyro recording). Kasdin power-of-two row: "
          f"nr = {next_pow2(cfg.n)}, first {cfg.n} samples kept. Expected adev: N / sqrt(tau) "
          f"for white, 0.664 B for flicker (tcbench's bank starts at 1 s, so it sits below the "
          f"floor at tau = 1 s); `noise.pink` has no amplitude parameter, so its level is not "
          f"comparable, and an Allan slope near -0.5 means its output is white, not 1/f.")


def main(argv: list[str] | None = None) -> int:
    parser = parser_for(__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--hours", type=float, default=24.0)
    parser.add_argument("--rate-hz", type=float, default=100.0)
    add_json(parser, DEFAULT_JSON, help_text=None)
    parser.add_argument("--child", choices=sorted(TASKS), help=argparse.SUPPRESS)
    parser.add_argument("--mode", choices=("time", "trace"), default="time", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    cfg = Config(args.hours, args.rate_hz)

    if args.child:
        task = TASKS[args.child]
        result = (measure_time(task, cfg, args.repeats) if args.mode == "time"
                  else measure_trace(task, cfg))
        print(json.dumps(result))
        return 0

    load_start = os.getloadavg()[0]
    rows: dict[str, dict[str, Any]] = {}
    for name, task in TASKS.items():
        print(f"measuring {name} ...", file=sys.stderr, flush=True)
        rows[name] = {**in_child(name, "time", args), **in_child(name, "trace", args),
                      "samples": cfg.n}
    libraries = versions("numpy", "scipy", "pandas", "allantools", "tcbench")
    load = (load_start, os.getloadavg()[0])
    report(rows, cfg, args, libraries, load)
    write_json(
        args.json,
        {"hours": args.hours, "rate_hz": args.rate_hz, "samples": cfg.n, "repeats": args.repeats,
         "versions": libraries, "load_average_1min": load, "rows": rows},
        final_newline=False,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
