"""Raw (uncompensated) figures of five simulated devices against the seed papers' raw values.

Simulates devices 0-4 through the MSRA room-temperature and full-temperature tests (seed 000
§3.1) and the gyro oven run (seed 001 §4.1), computes the papers' metrics, measures how far
runs of one device land apart (against seed 000's pairs of test sets), and rewrites this
folder's README.md tables and figures. Run from the repository root:

    python experiments/raw-sensors/run.py
"""

from __future__ import annotations

import argparse
import string
import time
from pathlib import Path

import numpy as np

from tcbench.metrics import gyro
from tcbench.metrics.report import analyse
from tcbench.plots import recording_overview
from tcbench.sensors import runs, timing
from tcbench.sensors.devices import AGEING_DAYS
from tcbench.sensors.kinds import unit
from tcbench.sensors.kinds.msra import SLOPE_REPEAT as MSRA_SLOPE_REPEAT
from tcbench.sensors.kinds.gyro import gyro_oven
from tcbench.sensors.simulate import simulate_recording

HERE = Path(__file__).resolve().parent
DEVICES = range(5)
# metric: (label, paper raw values, source, unit, format)
PAPER = {
    "after_30min_ug": ("MSRA zero-bias stability after 30 min", "186.47, 109.56", "000 Table 1", "µg", "{:.0f}"),
    "after_20min_ug": ("MSRA zero-bias stability after 20 min", "231.63, 136.38", "000 Table 1", "µg", "{:.0f}"),
    "zero_start_ug": ("MSRA zero-start zero-bias stability", "283.05, 227.98", "000 Table 1", "µg", "{:.0f}"),
    "sf_variation_ppm": ("MSRA scale-factor variation, −40…60 °C", "20 600, 2 153.2", "000 Table 2", "ppm", "{:.0f}"),
    "bias_variation_ug": ("MSRA bias variation, −40…60 °C", "39 152, 32 873", "000 Table 2", "µg", "{:.0f}"),
    "arw_deg_per_sqrt_h": ("gyro angle random walk", "0.531 (printed °/h/√Hz)", "001 §4.2", "°/√h", "{:.3f}"),
    "bias_instability_dph": ("gyro bias stability", "32.7364", "001 §4.2", "°/h", "{:.1f}"),
    "drift_60_to_m40_dps": ("gyro output drift, 60 → −40 °C", "≈ 0.035 (0.115 → 0.15)", "001 §4.2", "°/s", "{:.3f}"),
    "drift_noise_free_dps": ("  the same, noise-free model", "", "", "°/s", "{:.3f}"),
}


# Run to run: seed 000's raw metrics of its two test sets (same device, same protocol).
RUN_METRICS = {
    "sf_variation_ppm": ("scale-factor variation", "ppm", (20600.0, 2153.2), "Table 2"),
    "bias_variation_ug": ("bias variation", "µg", (39152.0, 32873.0), "Table 2"),
    "after_30min_ug": ("zero-bias stability after 30 min", "µg", (186.47, 109.56), "Table 1"),
    "after_20min_ug": ("zero-bias stability after 20 min", "µg", (231.63, 136.38), "Table 1"),
    "zero_start_ug": ("zero-start zero-bias stability", "µg", (283.05, 227.98), "Table 1"),
}
RUNS = 10  # runs per device


def run_seeds(device: int) -> list[int]:
    """Device ``device``'s runs: its table run (seed = device) first, then every len(DEVICES)-th
    seed, so no two devices share a run seed (a run seed fixes the power-on and the noise)."""
    return [device + len(DEVICES) * k for k in range(RUNS)]


def runs_of(device: int, replay: bool) -> tuple[np.ndarray, np.ndarray]:
    """The raw MSRA metrics (rows: runs, columns: RUN_METRICS) of one device's runs and each
    run's room-temperature self-heating (°C). ``replay``: every run replays the first run's power-on
    (only the noise and the room's ambient wander differ)."""
    seeds = run_seeds(device)
    rows, heat = [], []
    for seed in seeds:
        m: dict[str, float] = {}
        for protocol in ("fulltemp", "roomtemp"):
            rec = simulate_recording("msra", protocol, device, seed, power_on=seeds[0] if replay else None)
            m |= analyse(rec).metrics
        heat.append(float(rec.meta.extra["self_heating_c"]))  # rec: the room-temperature run
        rows.append([m[k] for k in RUN_METRICS])
    return np.array(rows), np.array(heat)


def spread(values: np.ndarray) -> dict[str, np.ndarray]:
    """Run-to-run spread of one metric, ``values`` shaped (devices, runs): per device the max/min
    ratio and the coefficient of variation (ddof=1), and the ratio of every pair of runs."""
    i, j = np.triu_indices(values.shape[1], 1)
    a, b = values[:, i], values[:, j]
    return {"ratio": values.max(1) / values.min(1),
            "cv": values.std(1, ddof=1) / values.mean(1),
            "pairs": (np.maximum(a, b) / np.minimum(a, b)).ravel()}


def pair_stats(pair: tuple[float, float]) -> tuple[float, float]:
    """The paper pair's ratio and coefficient of variation (ddof=1)."""
    v = np.array(pair)
    return float(v.max() / v.min()), float(v.std(ddof=1) / v.mean())


def run_to_run() -> dict[str, np.ndarray]:
    """Both tiers' metrics, (devices, runs, metrics), and the self-heating of the new power-ons."""
    out: dict[str, np.ndarray] = {}
    for tier, replay in (("power_on", False), ("replay", True)):
        measured = [runs_of(d, replay) for d in DEVICES]
        out[tier] = np.stack([m for m, _ in measured])
        if not replay:
            out["heat"] = np.stack([h for _, h in measured])
    return out


def measure(device: int) -> dict[str, float]:
    """All raw metrics of one device (run seed = device seed)."""
    m: dict[str, float] = {}
    for sensor, protocol in (("msra", "roomtemp"), ("msra", "fulltemp"), ("gyro", "oven")):
        m |= analyse(simulate_recording(sensor, protocol, device, device)).metrics
    quiet = unit("gyro", device).model.without("white_noise", "bias_instability", "quantisation")
    prof = gyro_oven()
    y = quiet.simulate(prof, np.random.default_rng(0))
    m["drift_noise_free_dps"] = gyro.drift_dps(prof.t_s, prof.temp_c, y)
    return m


def figures() -> list[str]:
    """Overview plots of device 0 in each test."""
    names = []
    for sensor, protocol in (("msra", "roomtemp"), ("msra", "fulltemp"), ("gyro", "oven")):
        rec = simulate_recording(sensor, protocol, 0, 0)
        name = f"{sensor}-{protocol}-dev0.png"
        unit_label = "Hz" if sensor == "msra" else "°/s"
        recording_overview(HERE / name, rec.time_s, rec.temperature_c, rec.output,
                           f"output ({unit_label})", f"{rec.meta.device_id}, {protocol}", max_points=6000)
        names.append(name)
    return names


def table(results: list[dict[str, float]]) -> str:
    head = "| metric | unit | paper raw | source | " + " | ".join(f"dev {d}" for d in DEVICES) + " | sim. range |"
    rule = "|---|---|---|---|" + "---|" * len(results) + "---|"
    rows = [head, rule]
    for key, (label, paper, source, unit_, fmt) in PAPER.items():
        values = [r[key] for r in results]
        cells = [fmt.format(v) for v in values]
        span = f"{fmt.format(min(values))} … {fmt.format(max(values))}"
        rows.append(f"| {label} | {unit_} | {paper} | {source} | " + " | ".join(cells) + f" | {span} |")
    return "\n".join(rows)


class Prose(string.Formatter):
    """``str.format`` with percentages as this README writes them: ``{x:.1%}`` gives "12.3 %" and
    ``{x:.0p}`` the bare number, "12" (for ranges: "{lo:.0p}–{hi:.0%}" gives "12–34 %")."""

    def format_field(self, value: object, format_spec: str) -> str:
        if format_spec.endswith(("%", "p")) and isinstance(value, (int, float)):
            number = format(100.0 * value, format_spec[:-1] + "f")
            return number + (" %" if format_spec.endswith("%") else "")
        return super().format_field(value, format_spec)


def run_table(rr: dict[str, np.ndarray]) -> str:
    """The run-to-run table: per metric, the paper pair and both tiers' spread."""
    rows = ["| metric | seed 000 pair | pair ratio | pair CV | runs differ by | max/min of 10 runs "
            "(median / max over devices) | CV (median) | two-run ratio (median) | two-run pairs ≥ pair ratio |",
            "|---|---|---|---|---|---|---|---|---|"]
    for n, (label, unit_, pair, source) in enumerate(RUN_METRICS.values()):
        ratio, cv = pair_stats(pair)
        for tier, name in (("power_on", "new power-on"), ("replay", "noise only (replay)")):
            sp = spread(rr[tier][:, :, n])
            head = (f"| {label} ({unit_}, {source}) | {pair[0]:g}, {pair[1]:g} | {ratio:.2f} | {cv:.2f} |"
                    if tier == "power_on" else "| | | | |")
            rows.append(f"{head} {name} | {np.median(sp['ratio']):.3f} / {sp['ratio'].max():.3f} | "
                        f"{np.median(sp['cv']):.4f} | {np.median(sp['pairs']):.3f} | "
                        f"{100.0 * np.mean(sp['pairs'] >= ratio):.1f} % |")
    return "\n".join(rows)


def run_numbers(rr: dict[str, np.ndarray], results: list[dict[str, float]]) -> dict[str, float]:
    """The figures the run-to-run prose quotes."""
    keys = list(RUN_METRICS)
    out: dict[str, float] = {}
    for n, key in enumerate(keys):
        ratio, cv = pair_stats(RUN_METRICS[key][2])
        for tier in ("power_on", "replay"):
            sp = spread(rr[tier][:, :, n])
            out |= {f"{key}.{tier}.max": float(sp["ratio"].max()), f"{key}.{tier}.pair": float(np.median(sp["pairs"])),
                    f"{key}.{tier}.share": float(np.mean(sp["pairs"] >= ratio)),
                    f"{key}.{tier}.cv": float(np.median(sp["cv"])),
                    f"{key}.{tier}.pairmax": float(sp["pairs"].max())}
        out |= {f"{key}.paper": ratio, f"{key}.paper_cv": cv}
    v = rr["power_on"]
    kept = v[:, :, keys.index("after_30min_ug")] / v[:, :, keys.index("zero_start_ug")]
    out |= {"kept_min": float(kept.min()), "kept_max": float(kept.max())}
    heat = rr["heat"]
    out["heat_r"] = float(np.median([np.corrcoef(heat[d], v[d, :, keys.index("zero_start_ug")])[0, 1]
                                     for d in range(heat.shape[0])]))
    sf = [r["sf_variation_ppm"] for r in results]
    out |= {"sf_lo": min(sf), "sf_hi": max(sf), "sf_lo_dev": float(np.argmin(sf)), "sf_hi_dev": float(np.argmax(sf))}
    bias = [r["bias_variation_ug"] for r in results]
    out |= {"bias_dev_ratio": max(bias) / min(bias)}
    out["runs"] = RUNS
    out["pairs"] = len(DEVICES) * RUNS * (RUNS - 1) // 2
    return out


def check_run_claims(n: dict[str, float]) -> list[str]:
    """The run-to-run prose's qualitative claims that the numbers no longer support."""
    bad = []
    if max(n[f"{k}.power_on.max"] for k in ("sf_variation_ppm", "bias_variation_ug")) > 1.05:
        bad.append("scale-factor/bias variation repeat between power-ons (ratio <= 1.05)")
    if n["zero_start_ug.power_on.share"] < 0.10:
        bad.append("the zero-start pair lies inside the simulated spread (>= 10 % of pairs reach it)")
    if not 0.0 < n["after_30min_ug.power_on.share"] < 0.10:
        bad.append("the after-30-min pair sits in the tail (0 < share of pairs < 10 %)")
    if n["after_30min_ug.replay.share"] >= n["after_30min_ug.power_on.share"]:
        bad.append("noise alone spreads less than a new power-on")
    return bad


RUN_TEXT = """## Run to run: two runs of one device against seed 000's pairs of test sets

Seed 000 gives its raw metrics for two test sets of one device under one protocol: Table 1's
zero-bias stability and Table 2's full-temperature scale-factor and bias variation. In tcbench a run
seed is a power-on (`tcbench/sensors/runs.py`), and each of devices 0-4 is run {runs} times here
(`simulate_recording("msra", "fulltemp"|"roomtemp", d, s)` with seeds s = d, d+{step}, …, d+{last}, the
first being the run in the table above, so no two devices share a run seed). The replay tier
runs the same seeds with `power_on=d`: every run replays the first run's power-on, and only the
sensor noise and the room's ambient wander (drawn with the profile) differ.

What a power-on draws (`runs.power_on`, `kinds.msra.msra_power_on`, `timing.draw_timing`):

- **turn-on** (MSRA): bias 100 µg (std; resonator 1's frequency moved), scale factor 50 ppm (std), the
  bias temperature slope {slope:.1%} (relative std), and ageing of 2 µg per day (std of the rate) over a
  uniform 0-{days:.0f} days since the device's first run;
- **hysteresis state**: uniform in −1…1, the start of the `hysteresis` effect. Only the consumer
  accelerometer's model has that effect; the MSRA has none, so this draw changes nothing here;
- **chamber timing**: ramp rate within ±{ramp:.0%} (uniform), each soak ±{soak:.0%} (uniform), start point
  {start:.1f} °C (std); a room-temperature run also gets another day's ambient ({ambient:.0f} °C std) and
  its self-heating scaled by {heat:.0%} (std);
- **thermometer**: the device's placement (offset 1-3 °C of either sign, gradient 0.1-1 °C per °C/min
  of heat flow) moves by {toff:.1f} °C (std) in offset and {tgrad:.0%} (relative std) in gradient. The raw
  metrics below read the output only (the thermometer labels the nodes), so this draw matters to
  compensation, not to this table.

{table}

Max/min is over the {runs} runs of one device; CV is std/mean (ddof=1) over them, median over the
five devices. The paper has one pair, so the closest comparison is the two-run columns: the median
ratio of the {pairs} pairs of runs of one device ({per_device} per device) and the share of them that differ by
at least the paper pair's ratio.

How close the simulated spread lands:

- **Zero-bias stability: close at zero start, at the edge after 20 and 30 min.** Zero start: the
  paper's pair differs by {zs_paper:.2f}×; two runs of one simulated device typically differ by
  {zs_pair:.2f}× and {zs_share:.0%} of pairs differ by at least {zs_paper:.2f}×. After 30 min the paper's pair differs by {a30_paper:.2f}× (after 20 min {a20_paper:.2f}×), the
  max/min of ten simulated runs reaches {a30_max:.2f}× ({a20_max:.2f}×), but only {a30_share:.1%}
  ({a20_share:.1%}) of two-run pairs differ by that much: the paper's pair sits in the tail of the
  simulated spread (its CV {a30_cv:.2f} against a median {a30_sim_cv:.2f}). The paper's two sets keep 66 % and 48 % of
  their zero-start stability after 30 min; simulated runs keep {kept_min:.0p}–{kept_max:.0%}. The spread is the
  power-on's: the self-heating amplitude correlates with the zero-start stability at r = {heat_r:.2f}
  (median over devices), and with noise alone (replay) two runs differ by {a30_rep_pair:.2f}× after 30 min
  and {a30_rep_share:.0%} of pairs reach {a30_paper:.2f}×.
- **Scale-factor variation: not close, and it cannot be.** The paper's pair differs by {sf_paper:.2f}×; simulated
  runs of one device differ by at most {sf_max:.4f}× (CV {sf_cv:.4f}). The variation over the six nodes is the
  device's scale-factor temperature coefficient gK times the spread of the node temperatures. A
  power-on moves the scale factor by a constant 50 ppm (it shifts K1's mean, and the variation, by
  5·10⁻⁵ relative) and does not touch gK; the chamber timing's changes of ramp rate and soak length
  are settled out by the 60 min soaks (thermal lag 6–14 min). A {sf_paper:.1f}× change would need gK
  to change {sf_paper:.1f}-fold between two power-ons of one part, the whole span of the device population (gK 60-600 ppm/K). In the table
  above it is the gap between two different devices (dev {sf_lo_dev:.0f}: {sf_lo:.0f} ppm, dev {sf_hi_dev:.0f}: {sf_hi:.0f} ppm,
  {sf_dev_ratio:.1f}×): the paper's two scale-factor figures behave like two different devices, not
  like two power-ons of one.
- **Bias variation: not close.** The paper's pair differs by {bv_paper:.2f}×; simulated runs by at most
  {bv_max:.4f}×. The bias variation is the bias temperature slope times the node spread, and a power-on
  changes the slope by {slope:.1%} (std): a {bv_pct:.0f} % change would be a {bv_sigma:.0f}σ draw. `devices.py`
  takes the {slope:.1%} from the paper's compensated test sets (33–37 µg left of a 39 000 µg span, Table 2):
  a compensation fitted on other data leaves that little only if the slope repeats to about that, not
  if it moves by {bv_pct:.0f} %. Between the five simulated devices the bias variation differs by up to
  {bias_dev_ratio:.2f}×: the paper's {bv_paper:.2f}× lies within the spread between devices, not within
  the spread between runs of one.
"""


def run_section(rr: dict[str, np.ndarray], results: list[dict[str, float]]) -> str:
    n = run_numbers(rr, results)
    for claim in check_run_claims(n):
        print(f"warning: the README's run-to-run prose claims that {claim}; the numbers no longer say so")
    return Prose().format(RUN_TEXT,
        table=run_table(rr), runs=RUNS, pairs=int(n["pairs"]), step=len(DEVICES),
        last=len(DEVICES) * (RUNS - 1), per_device=RUNS * (RUNS - 1) // 2,
        slope=MSRA_SLOPE_REPEAT, days=AGEING_DAYS, ramp=timing.RAMP_TOLERANCE, soak=timing.SOAK_JITTER,
        start=timing.START_JITTER_C, ambient=timing.AMBIENT_JITTER_C, heat=timing.SELF_HEATING_JITTER,
        toff=runs.THERMOMETER_OFFSET_JITTER_C, tgrad=runs.THERMOMETER_GRADIENT_JITTER,
        zs_paper=n["zero_start_ug.paper"], zs_pair=n["zero_start_ug.power_on.pair"],
        zs_share=n["zero_start_ug.power_on.share"],
        a30_paper=n["after_30min_ug.paper"], a20_paper=n["after_20min_ug.paper"],
        a30_max=n["after_30min_ug.power_on.max"], a20_max=n["after_20min_ug.power_on.max"],
        a30_share=n["after_30min_ug.power_on.share"], a20_share=n["after_20min_ug.power_on.share"],
        a30_cv=n["after_30min_ug.paper_cv"], a30_sim_cv=n["after_30min_ug.power_on.cv"],
        kept_min=n["kept_min"], kept_max=n["kept_max"], heat_r=n["heat_r"],
        a30_rep_pair=n["after_30min_ug.replay.pair"], a30_rep_share=n["after_30min_ug.replay.share"],
        sf_paper=n["sf_variation_ppm.paper"], sf_max=n["sf_variation_ppm.power_on.max"],
        sf_cv=n["sf_variation_ppm.power_on.cv"], sf_lo=n["sf_lo"], sf_hi=n["sf_hi"],
        sf_lo_dev=n["sf_lo_dev"], sf_hi_dev=n["sf_hi_dev"], sf_dev_ratio=n["sf_hi"] / n["sf_lo"],
        bv_paper=n["bias_variation_ug.paper"], bv_max=n["bias_variation_ug.power_on.max"],
        bv_pct=100.0 * (n["bias_variation_ug.paper"] - 1.0),
        bv_sigma=(n["bias_variation_ug.paper"] - 1.0) / MSRA_SLOPE_REPEAT, bias_dev_ratio=n["bias_dev_ratio"],
    )


README = """# Raw sensor figures: simulated devices against the seed papers

The simulators' default device population (`tcbench/sensors/devices.py`) is calibrated so
that the raw, uncompensated metrics of simulated units land near the raw figures that
the two seed papers report for their hardware. These tables are regenerated by

```bash
python experiments/raw-sensors/run.py      # ~{took}: 5 devices x 3 tests, 5 devices x 10 runs x 2 tests x 2 tiers, figures, README
```

Device *d* is `device_seed=d` with run seed *d*; every number comes from
`tcbench.metrics.report.analyse` on the simulated recording, the same code as
`tcbench simulate ... && tcbench metrics ...`.

{table}

Conventions: zero-bias stability is 1σ (ddof=1) of non-overlapping 10 s means of output / scale factor
from 30 min, 20 min and 0 min after power-on. Scale factor K1 = (U(+1g) − U(−1g))/2 and bias
B0 = (U(+0g) + U(−0g))/(U(+1g) − U(−1g))·g (eq. 12 with a plus sign); variation = std/mean of K1 and std of B0
over the six nodes (ddof=1). Gyro ARW is read in °/√h (seed 001 prints °/h/√Hz for a value that only fits
as °/√h), bias stability = Allan minimum / 0.664, both over τ ≤ T/10 of the whole oven run. Drift = mean output
over the last 10 min of the 60 °C soak minus the −40 °C soak.

## How the defaults were set, and where they differ from experiments/raw-sensors/README.md

- **MSRA bias variation.** With experiments/raw-sensors/README.md's resonator coefficients (c1 = −40 / −38.1 ppm/K, a 5 %
  mismatch) the bias moves by about 310 µg/K and its variation over −40…60 °C is about 11 000 µg, a
  third of the paper's 33 000–39 000 µg. The device population therefore draws a 11–15 % mismatch of the
  resonators' frequency coefficients (dU/dT ≈ −0.13 … −0.18 Hz/K, 650–900 µg/K). The bias
  variation also grows with the scale-factor coefficient gK through the 150 Hz built-in offset
  (B0 ≈ ΔF/S), so devices with large gK land above the paper's range (see the table).
- **MSRA scale-factor variation** comes from gK drawn log-uniformly in 60–600 ppm/K, which spans the
  paper's two datasets (2 153 and 20 600 ppm).
- **MSRA room temperature.** With the larger bias coefficient, the simulator's 2.5 °C self-heating (20 min)
  would give a zero-start stability of {hot_lo:.0f}–{hot_hi:.0f} µg (devices 0–4). The room-temperature protocol
  uses 1.1 °C self-heating with a 40 min time constant (instead of 20 min): the paper's stability after
  30 min is 48 % and 66 % of its zero-start value (the simulated devices: {kept_lo:.0p}–{kept_hi:.0%}), which a
  20 min settling cannot reproduce (it gives {fast_lo:.0p}–{fast_hi:.0%}).
- **Gyro.** experiments/raw-sensors/README.md's defaults are used as they are (bias 1.10u + 4.0e-3u² + 1.5e-4u³ °/h,
  3 °/h per °C/min, lag 8 min, ARW 0.52 °/√h, flicker B = 33 °/h), with a few per cent spread per device.
  The noise-free drift from 60 to −40 °C is {quiet_lo:.3f}–{quiet_hi:.3f} °/s, as in the paper. The measured drift scatters
  by up to ±{scatter:.3f} °/s around it (the table's runs): flicker noise of B = 33 °/h wanders by tens of °/h over the
  13 h between the two soaks (the standard deviation of the difference of two 10 min means 13 h apart is
  about 50 °/h for pure flicker at this B, measured). A single oven run therefore cannot pin the drift to better than that.

{run_to_run}
## Figures (device 0)

{figures}
"""


def settling() -> dict[str, float]:
    """Room-temperature figures the prose quotes (run seed = device seed): the zero-start stability
    with the simulator's 2.5 °C, 20 min self-heating, and the share of it left after 30 min with the
    default 1.1 °C settling in 20 min instead of 40."""
    hot, fast = [], []
    for d in DEVICES:
        hot.append(analyse(simulate_recording("msra", "roomtemp", d, d, self_heating_c=2.5,
                                              self_heating_tau_s=1200.0)).metrics["zero_start_ug"])
        m = analyse(simulate_recording("msra", "roomtemp", d, d, self_heating_tau_s=1200.0)).metrics
        fast.append(m["after_30min_ug"] / m["zero_start_ug"])
    return {"hot_lo": min(hot), "hot_hi": max(hot), "fast_lo": min(fast), "fast_hi": max(fast)}


def prose_numbers(results: list[dict[str, float]]) -> dict[str, float]:
    """The figures of the table's runs that the prose quotes."""
    kept = [r["after_30min_ug"] / r["zero_start_ug"] for r in results]
    quiet = [r["drift_noise_free_dps"] for r in results]
    scatter = max(abs(r["drift_60_to_m40_dps"] - r["drift_noise_free_dps"]) for r in results)
    return {"kept_lo": min(kept), "kept_hi": max(kept), "quiet_lo": min(quiet), "quiet_hi": max(quiet),
            "scatter": scatter}


def main() -> None:
    argparse.ArgumentParser(description=__doc__).parse_args()
    start = time.perf_counter()
    results = [measure(d) for d in DEVICES]
    rr = run_to_run()
    names = figures()
    figs = "\n".join(f"![{n}]({n})" for n in names)
    numbers = prose_numbers(results) | settling()
    section = run_section(rr, results)
    took = f"{10 * max(1, round((time.perf_counter() - start) / 10.0))} s"
    text = Prose().format(README, table=table(results), figures=figs, run_to_run=section, took=took, **numbers)
    (HERE / "README.md").write_text(text)
    print(table(results))
    print()
    print(run_table(rr))
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
