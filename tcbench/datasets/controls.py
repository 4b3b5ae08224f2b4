"""Control recordings (nothing hidden) of any form: length, rate, continuous or in bursts.

The open-world controls (:func:`tcbench.datasets.open_world.open_world_recording` with no kind)
are 8-12 h at 1 Hz. :func:`control_recording` draws the same kind of control at another form:
the heat-and-cool staircase of :func:`~tcbench.datasets.concealed.concealed_profile` sized to
the length (:meth:`~tcbench.datasets.concealed.Sizing.for_duration`), sampled at ``rate_hz``;
the device with every effect removed, its white noise density times a log-uniform factor 1-3
(so the per-sample sigma grows as sqrt(rate)); the thermometer as in the concealed set. In
bursts, only ``burst_s`` of every ``period_s`` is kept (the logger sleeps the rest), starting
at a random phase. Without the noise it *is* the minimal model, so any named effect is a false
alarm. Every draw comes from generators spawned from ``np.random.SeedSequence(seed)``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from tcbench.datasets.concealed import (
    NOISE_FACTOR,
    THERMOMETER_NOISE_C,
    THERMOMETER_STEP_C,
    Sizing,
    concealed_profile,
    device_without_effects,
)
from tcbench.sensors import noise
from tcbench.sensors.recording import Recording, make_recording
from tcbench.sensors.kinds import profile_input


@dataclass(frozen=True)
class Form:
    """A recording's form: nominal length (s), rate (Hz) and, in bursts, ``burst_s`` kept of every
    ``period_s`` (both 0 for a continuous record)."""

    duration_s: float
    rate_hz: float
    burst_s: float = 0.0
    period_s: float = 0.0

    @property
    def bursty(self) -> bool:
        return self.burst_s > 0.0

    @property
    def samples(self) -> int:
        """About how many samples a record of this form keeps."""
        share = self.burst_s / self.period_s if self.bursty else 1.0
        return int(self.duration_s * self.rate_hz * share)


def bursts_for(duration_s: float) -> tuple[float, float]:
    """A burst pattern sized to the record: a period of 1/12 of it within 1-10 min, bursts of a
    sixth of the period (10 s every minute for a 10-min record, 100 s every 10 min for days)."""
    period_s = float(np.clip(duration_s / 12.0, 60.0, 600.0))
    return period_s / 6.0, period_s


def _kept(t_s: np.ndarray, form: Form, rng: np.random.Generator) -> np.ndarray:
    """Which samples a bursty logger keeps (all for a continuous form)."""
    if not form.bursty:
        return np.ones(t_s.size, dtype=bool)
    phase_s = rng.uniform(0.0, form.period_s)
    return np.mod(t_s + phase_s, form.period_s) < form.burst_s


def control_recording(sensor: str, form: Form, seed: int) -> tuple[Recording, dict[str, float]]:
    """A control of ``form`` (nothing hidden) and its truth (white sigma per sample, span, seed)."""
    streams = np.random.SeedSequence(int(seed)).spawn(6)
    r_profile, r_device, r_sim, r_scale, r_white, r_thermo = (np.random.default_rng(s) for s in streams)
    # one burst period longer, so the kept bursts still span the requested length
    sizing = Sizing.for_duration(form.duration_s + form.period_s)
    profile = concealed_profile(sensor, r_profile, sizing, form.rate_hz)
    device_seed = int(r_device.integers(0, 10_000))
    model, default_sigma = device_without_effects(sensor, device_seed, form.rate_hz)
    sigma = default_sigma * float(np.exp(r_scale.uniform(*np.log(NOISE_FACTOR))))
    keep = _kept(profile.t_s, form, r_scale)
    base = model.simulate(profile, r_sim)
    n = profile.t_s.size
    output = base + sigma * noise.white(n, 1.0, r_white)
    reading = profile.temp_c + r_thermo.standard_normal(n) * THERMOMETER_NOISE_C
    thermometer = noise.quantise(reading, THERMOMETER_STEP_C)
    t_kept = profile.t_s[keep]
    truth = {"white_sigma": float(sigma), "span_s": float(t_kept[-1] - t_kept[0]), "seed": float(seed),
             "samples": float(keep.sum())}
    extra = {"form": asdict(form), "control": truth, "device_seed": device_seed, "profile": dict(profile.info)}
    rec = make_recording(t_kept, thermometer[keep], profile_input(profile)[keep], output[keep], sensor=sensor,
                         sample_rate_hz=form.rate_hz, device_id=f"form-control-{sensor}-{seed}", extra=extra)
    return rec, truth
