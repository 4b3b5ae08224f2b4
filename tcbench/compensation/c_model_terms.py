"""The terms of a diagnosed model as a device runs them (:mod:`.c_export`'s ``model`` kind): for
each term id, in one table (:data:`TERMS`), its state, its numpy reference and its C update lines.

A term is either a stage of the die temperature (``thermal_lag``: run first, in the model's
order, each on its own first-order filter) or an addition to the offset, computed on the die
temperature (the others, in the model's order). The numpy reference is what the compiled code is
checked against, operation for operation (:func:`~.c_export.streamed_offset`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

Effect = dict[str, Any]  # one term of a model spec: its "id" and its parameters


def c_literal(v: float) -> str:
    """A C double literal that reads back exactly (hexadecimal)."""
    v = float(v)
    if np.isinf(v):
        return "HUGE_VAL" if v > 0 else "-HUGE_VAL"
    return v.hex()


def lag(x: np.ndarray, dt: np.ndarray, tau_s: float) -> np.ndarray:
    """``y += (1 - exp(-dt / tau)) (x - y)``, ``y = x`` at the first sample (``tau_s <= 0``: x)."""
    if tau_s <= 0 or x.size == 0:
        return x.copy()
    gain = 1.0 - np.exp(-dt / tau_s)
    out = np.empty_like(x)
    y = float(x[0])
    for i, (xi, g) in enumerate(zip(x.tolist(), gain.tolist())):
        y = y + g * (xi - y)
        out[i] = y
    return out


@dataclass(frozen=True)
class Signals:
    """What a term reads at every sample: the device's intervals (``dt[0] = 0``), the thermometer,
    the die temperature and the model's reference temperature."""

    dt: np.ndarray
    temp: np.ndarray
    die: np.ndarray
    ref_c: float


@dataclass(frozen=True)
class Lines:
    """A term's C update: its lines, its floating-point operations and its ``exp`` calls per sample."""

    lines: list[str]
    flops: int
    calls: int = 0


@dataclass(frozen=True)
class ModelTerm:
    """One term's device form. ``slot``: the name of its own state (None: none; ``shared``: one
    slot all such terms of a model share, after the others); ``die_stage``: it filters the die
    temperature (``reference`` then returns the new die temperature, not an offset);
    ``reference(e, signals)``: its numpy output; ``c_lines(e, ref_c, at)``: its C update, its state
    at ``s->memory[at]``."""

    slot: str | None
    reference: Callable[[Effect, Signals], np.ndarray]
    c_lines: Callable[[Effect, float, int], Lines]
    die_stage: bool = False
    shared: bool = False


def _filter_lines(e: Effect, at: int, then: str) -> list[str]:
    """A first-order filter of the die temperature in ``s->memory[at]``, then the line ``then``."""
    return [f"    if (first) s->memory[{at}] = die;",
            f"    else s->memory[{at}] += ((R)1 - TC_EXP(-dt_s / (R){c_literal(e['tau_s'])})) * (die - s->memory[{at}]);",
            then]


def _rate(e: Effect, s: Signals) -> np.ndarray:
    rate = np.r_[0.0, np.diff(s.temp) / np.where(s.dt[1:] > 0, s.dt[1:], 1.0)] if s.dt.size else s.dt
    return e["coef_per_c_per_s"] * rate


def _rate_lines(e: Effect, ref_c: float, at: int) -> Lines:
    return Lines([f"    if (!first && dt_s > 0) offset += (R){c_literal(e['coef_per_c_per_s'])} * "
                  f"((temperature_c - s->memory[{at}]) / dt_s);",
                  f"    s->memory[{at}] = temperature_c;"], 4)


def _play(e: Effect, s: Signals) -> np.ndarray:
    """The play operator of half-width ``width_c`` on the die temperature, per sample."""
    w = e["width_c"]
    state = np.empty(s.die.size)
    p = float(s.die[0]) - float(np.clip(e["start_state"], -1.0, 1.0)) * w if s.die.size else 0.0
    for i, x in enumerate(s.die.tolist()):
        p = min(max(p, x - w), x + w)
        state[i] = (x - p) / w
    return e["amplitude"] * state


def _play_lines(e: Effect, ref_c: float, at: int) -> Lines:
    w, start = c_literal(e["width_c"]), c_literal(float(np.clip(e["start_state"], -1.0, 1.0)))
    return Lines([f"    if (first) s->memory[{at}] = die - (R){start} * (R){w};",
                  f"    if (s->memory[{at}] < die - (R){w}) s->memory[{at}] = die - (R){w};",
                  f"    if (s->memory[{at}] > die + (R){w}) s->memory[{at}] = die + (R){w};",
                  f"    offset += (R){c_literal(e['amplitude'])} * ((die - s->memory[{at}]) / (R){w});"], 6)


def _cubic_lines(e: Effect, ref_c: float, at: int) -> Lines:
    return Lines([f"    {{ R d = die - (R){c_literal(ref_c)}; offset += (R){c_literal(e['c3_per_c3'])} * (d * d * d); }}"], 5)


def _bump(e: Effect, s: Signals) -> np.ndarray:
    return e["amplitude"] * np.exp(-0.5 * ((s.die - e["centre_c"]) / e["width_c"]) ** 2)


def _bump_lines(e: Effect, ref_c: float, at: int) -> Lines:
    return Lines([f"    {{ R z = (die - (R){c_literal(e['centre_c'])}) / (R){c_literal(e['width_c'])}; "
                  f"offset += (R){c_literal(e['amplitude'])} * TC_EXP((R)-0.5 * (z * z)); }}"], 6, 1)


TERMS: dict[str, ModelTerm] = {
    "thermal_lag": ModelTerm(
        "die lag", lambda e, s: lag(s.die, s.dt, e["tau_s"]),
        lambda e, ref_c, at: Lines(_filter_lines(e, at, f"    die = s->memory[{at}];"), 5, 1), die_stage=True),
    "temperature_rate": ModelTerm("last temperature", _rate, _rate_lines, shared=True),
    "hysteresis": ModelTerm("play operator", _play, _play_lines),
    "temperature_cubic": ModelTerm(None, lambda e, s: e["c3_per_c3"] * (s.die - s.ref_c) ** 3, _cubic_lines),
    "temperature_bump": ModelTerm(None, _bump, _bump_lines),
    "second_node": ModelTerm(
        "second node", lambda e, s: e["coef_per_c"] * (lag(s.die, s.dt, e["tau_s"]) - s.die),
        lambda e, ref_c, at: Lines(_filter_lines(
            e, at, f"    offset += (R){c_literal(e['coef_per_c'])} * (s->memory[{at}] - die);"), 7, 1)),
}


def slots(effects: list[Effect]) -> list[str]:
    """A model's state, by name: each term's own (``<slot> <index>``), then the shared ones."""
    own = [f"{TERMS[e['id']].slot} {k}" for k, e in enumerate(effects)
           if TERMS[e["id"]].slot is not None and not TERMS[e["id"]].shared]
    shared = dict.fromkeys(TERMS[e["id"]].slot for e in effects if TERMS[e["id"]].shared)
    return own + list(shared)  # type: ignore[arg-type]


def slot_of(effects: list[Effect], k: int, names: list[str]) -> int:
    """Where term ``k`` keeps its state among the model's ``names`` (:func:`slots`)."""
    term = TERMS[effects[k]["id"]]
    return names.index(term.slot if term.shared else f"{term.slot} {k}")


def die_temperature(effects: list[Effect], dt: np.ndarray, temp: np.ndarray) -> np.ndarray:
    """The thermometer through the model's die stages, in order."""
    die = temp.copy()
    for e in effects:
        if TERMS[e["id"]].die_stage:
            die = TERMS[e["id"]].reference(e, Signals(dt, temp, die, 0.0))
    return die
