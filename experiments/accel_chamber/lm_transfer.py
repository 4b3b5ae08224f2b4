"""Why BP trained by Levenberg-Marquardt does not carry to a new power-on of the accel chamber.

Trains BP (random start, LM; ``--seed``) on the ``next_run`` tier of device 0 and reports, per test
cycle: the share of its rows whose [T, dT/dt] lies outside the training box, and the drift (µg)
of the network's compensation as trained and with its inputs clamped to that box (as
``tcbench calibrate`` clamps them).

    python experiments/accel_chamber/lm_transfer.py --seed 0
"""

from __future__ import annotations

import argparse

import numpy as np

from tcbench.metrics.accelerometer import zero_bias_stability_ug
from tcbench.tasks.msra_env import MSRACompensationEnv


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--split", default="next_run")
    ns = ap.parse_args()
    env = MSRACompensationEnv(task="accel_chamber", learner="bp", learner_params={"training": "lm"}, split=ns.split)
    env.reset(seed=ns.seed)
    env.score()
    assert env.data is not None and env.learner is not None and env._x is not None
    low, high = env._x.min(axis=0), env._x.max(axis=0)
    print(f"training box: T {low[0]:.2f}..{high[0]:.2f} °C, dT/dt {low[1]:.4f}..{high[1]:.4f} °C/s")
    for tr in env.data.test:
        x, _ = env.data.features(tr.recording)
        outside = np.any((x < low) | (x > high), axis=1).mean()
        t, out = tr.recording.time_s, tr.recording.output
        as_trained = zero_bias_stability_ug(t, out - env.learner.predict(x), 1.0)
        clamped = zero_bias_stability_ug(t, out - env.learner.predict(np.clip(x, low, high)), 1.0)
        raw = zero_bias_stability_ug(t, out, 1.0)
        print(f"{tr.name}: {outside:.1%} of rows outside the box; drift raw {raw:.0f}, "
              f"as trained {as_trained:.0f}, inputs clamped {clamped:.0f} µg")


if __name__ == "__main__":
    main()
