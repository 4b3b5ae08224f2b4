"""The base of a library term: one effect of :mod:`tcbench.sensors.effects` as the diagnosis
models, reports and explains it, and the registry that finds a term by its id.

A subclass sets the class attributes (``id``, ``shape``, ``effect``, ``confirm_with``, ...) and
implements :meth:`Term.explanation` and :meth:`Term.params`; a regressor also implements
:meth:`Term.column`. Two kinds of term are no regressor: noise (``deterministic = False``:
``bias_instability``, judged from the residual's Allan deviation) and an input transform
(``transforms_temperature``: ``thermal_lag``, which moves the whole model to the die temperature
its :meth:`Term.model_temperature` gives; :func:`temperature_transform` finds it).
Defining the subclass registers it: :func:`term` finds it by id, :func:`terms` lists them all
in the order they were defined. Installed packages add terms under the entry-point group
``tcbench.terms`` (``my_effect = "pkg.module:MyEffectTerm"``, the name being the term's id); they
are imported once, on the first look-up, and come after the built-in ones. The term's effect must
be known to the effect library (a built-in, or an entry point of ``tcbench.effects``). A plugin
that fails to import, names no :class:`Term`, clashes with a built-in id or models an unknown
effect is skipped and listed by :func:`broken_terms`. The open-world terms (:mod:`.open_base`)
share the registry: :func:`terms` lists the library's, ``terms(open=True)`` the open world's.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from tcbench.diagnose.signals import DiagnosisData
from tcbench.plugins import PluginRegistry
from tcbench.sensors.effects import Effect, Signals, effect_class

TERMS_GROUP = "tcbench.terms"
_REGISTRY: dict[str, Term] = {}
_NO_DRAW = np.random.default_rng(0)  # the deterministic effects a column comes from never draw from it


def g3(x: float) -> str:
    """A number in an explanation: three significant digits."""
    return f"{x:.3g}"


@dataclass(frozen=True)
class Extent:
    """What a library finding needs from the recording: its time span (s), its temperature
    band (degC, smoothed thermometer) and the output unit."""

    t_start_s: float
    t_end_s: float
    temp_low_c: float
    temp_high_c: float
    unit: str

    @classmethod
    def of(cls, data: DiagnosisData) -> Extent:
        """The extent of prepared ``data``."""
        return cls(float(data.t_s[0]), float(data.t_s[-1]), float(np.min(data.temp_c)), float(np.max(data.temp_c)),
                   data.unit)


def signals(data: DiagnosisData, temp_c: np.ndarray, ref_c: float = 0.0) -> Signals:
    """What an effect of the library sees on ``data``: its clock, ``temp_c`` as both the
    thermometer and the die temperature, the thermometer's slope, the input (as the
    acceleration and as the rate) and the mean sample interval."""
    dt_s = float(data.t_s[-1] - data.t_s[0]) / (data.t_s.size - 1) if data.t_s.size > 1 else 1.0
    return Signals(t_s=data.t_s, dt_s=dt_s, temp_meas_c=temp_c, temp_die_c=temp_c,
                   temp_rate_c_per_s=data.rate_c_per_s, accel_g=data.input, cross_g=np.zeros_like(data.input),
                   rate_dps=data.input, ref_c=ref_c)


class Term(ABC):
    """One effect of the library in the diagnosis.

    - ``id``, ``effect``: its id and its class in the effect library (the same id);
    - ``shape``: the shape its signature takes in a residual (docs/concepts/diagnosis-report.md, shapes);
    - ``param``, ``grid``: the nonlinear parameter searched and its grid (None: none);
    - ``deterministic``: a model term of the forward selection (False: noise, judged from the
      residual's Allan deviation);
    - ``confirm_with``: the measurement that would confirm it;
    - ``confusable``: ``{other id: the test that would tell the two apart}``, declared on one
      side of each pair (:meth:`partners` gives both);
    - ``flicker_mimics``: a slow random excursion of the bias can look like it;
    - ``cached``: its column is costly; the designer keeps it per value and model temperature;
    - ``transforms_temperature``: an input transform, not a column: at its searched value the
      whole model runs on :meth:`model_temperature` instead of the smoothed thermometer;
    - ``open_world``: structure outside the library (:class:`~.open_base.OpenTerm`), not a
      candidate of the library's forward selection;
    - ``units``: ``{parameter name: its unit}`` for the report, ``{unit}`` standing for the
      output unit, where the name does not say it (a name ending ``_s`` is in s, ``_c`` in degC);
    - ``gain_name``, ``gain_label``: what its evidence's gain is, for a term not judged by the
      held-out gain (``bias_instability``: an Allan ratio), in the report's table and on the
      evidence plot's axis (None: the penalised held-out gain).
    """

    id: ClassVar[str] = ""
    effect: ClassVar[type[Effect]]
    shape: ClassVar[str] = ""
    param: ClassVar[str | None] = None
    grid: ClassVar[np.ndarray | None] = None
    deterministic: ClassVar[bool] = True
    confirm_with: ClassVar[str] = ""
    confusable: ClassVar[Mapping[str, str]] = {}
    flicker_mimics: ClassVar[bool] = False
    cached: ClassVar[bool] = False
    transforms_temperature: ClassVar[bool] = False
    open_world: ClassVar[bool] = False
    units: ClassVar[Mapping[str, str]] = {}
    gain_name: ClassVar[str | None] = None
    gain_label: ClassVar[str | None] = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if not cls.id:
            return  # an intermediate base
        if cls.id in _REGISTRY:
            raise ValueError(f"term {cls.id!r} is registered twice (there is a term of that id already)")
        if cls.id != cls.effect.id:
            raise ValueError(f"term {cls.id!r} models effect {cls.effect.id!r}: the ids must match")
        _REGISTRY[cls.id] = cls()

    def unit_of(self, name: str, unit: str) -> str | None:
        """The unit of its parameter ``name`` when the output is in ``unit`` (None: not in :attr:`units`)."""
        u = self.units.get(name)
        return None if u is None else u.format(unit=unit)

    def grid_values(self) -> list[float | None]:
        """Values of the nonlinear parameter searched (``[None]`` if it has none)."""
        return [None] if self.grid is None else list(self.grid)

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        """The regressor at nonlinear parameter ``value`` on the model temperature ``temp_c``
        (``centre_c`` and ``half_range_c`` scale the temperature as the minimal model does)."""
        raise ValueError(f"effect {self.id!r} has no regressor")

    def model_temperature(self, data: DiagnosisData, value: float) -> np.ndarray:
        """The model temperature (degC) with this input transform at ``value``, for a term that
        :attr:`transforms_temperature`."""
        raise ValueError(f"term {self.id!r} does not transform the model temperature")

    def n_params(self, value: Any) -> int:
        """Parameters it adds to the minimal model at ``value``: its coefficient and its searched value."""
        return 1 + (value is not None)

    def past_grid(self, data: DiagnosisData) -> float | None:
        """How far the search may go past the grid's top when the best value is there, or None."""
        return None

    def skip(self, data: DiagnosisData) -> str | None:
        """Why ``data`` cannot show this effect at all, or None."""
        return None

    def where(self, extent: Extent) -> dict[str, Any]:
        """Where the effect shows in a recording of ``extent`` (report contract ``where``)."""
        if self.shape.startswith("temperature_"):
            return {"temperature_c": [round(extent.temp_low_c, 3), round(extent.temp_high_c, 3)]}
        return {}

    @abstractmethod
    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        """What the data showed and what physics does that, with the fitted ``params``."""

    @abstractmethod
    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        """The fitted coefficient ``coef`` of the column (and searched ``value``) as the effect
        library's parameters."""

    def unit_effect(self, value: float | None = None) -> Effect:
        """The library effect with a unit coefficient (and ``value`` as its nonlinear parameter):
        its output term is the column, where the design uses the simulator's formula."""
        raise NotImplementedError(f"term {self.id!r} does not build its column from its effect")

    def effect_column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray) -> np.ndarray:
        """The output term of :meth:`unit_effect` on ``data`` with ``temp_c`` as the temperature."""
        return self.unit_effect(value).term(signals(data, temp_c), _NO_DRAW)

    def partners(self) -> dict[str, str]:
        """``{other term id: test that tells the two apart}`` for every pair this term is in."""
        out = dict(self.confusable)
        for other in _registry().values():
            if self.id in other.confusable:
                out[other.id] = other.confusable[self.id]
        return out


class _TermPlugins(PluginRegistry[Term]):
    """The entry points of ``tcbench.terms``; importing one defines (and so registers) its term,
    which is taken back out of the registry if the checks fail."""

    def check_class(self, name: str, cls: Any) -> None:
        super().check_class(name, cls)
        if cls.id != name:
            raise TypeError(f"entry point {name!r} names term {cls.id!r}: the name must be the term's id")
        if type(_REGISTRY.get(name)) is not cls:
            raise ValueError(f"term {name!r} did not register")
        if effect_class(name) is not cls.effect:
            raise ValueError(f"term {name!r} models effect {cls.effect.__module__}.{cls.effect.__name__}, which the "
                             f"effect library does not know as {name!r}: declare it under the entry-point group "
                             "tcbench.effects")

    def _load_one(self, name: str) -> Any:
        before = set(_REGISTRY)
        entry = super()._load_one(name)
        if entry is None:
            for added in set(_REGISTRY) - before:
                del _REGISTRY[added]
        return entry


_PLUGINS = _TermPlugins(TERMS_GROUP, Term, "term")
_loaded = False


def _registry() -> dict[str, Term]:
    """The registry, with the installed terms imported on the first call."""
    global _loaded
    if not _loaded:
        _loaded = True
        _PLUGINS.available()
    return _REGISTRY


def broken_terms() -> dict[str, str]:
    """Installed terms that failed to load, with their error."""
    _registry()
    return _PLUGINS.broken()


def term_source(term_id: str) -> str:
    """Where term ``term_id`` comes from: ``tcbench`` or the distribution that installed it."""
    if type(term(term_id)).__module__.startswith(f"{__package__}."):
        return "tcbench"
    entry = _PLUGINS.available().get(term_id)
    return entry.package if entry is not None else "__main__"


def term(term_id: str) -> Term:
    """The registered term ``term_id``, or the open-world term of a further instance of it
    (``bias_step_2``: a second step, as the effect library names it); ``KeyError`` naming the
    known ones otherwise."""
    registry = _registry()
    if term_id in registry:
        return registry[term_id]
    cls = effect_class(term_id)  # a further instance's effect is its term's
    if cls is not None and cls.id != term_id and cls.id in registry and registry[cls.id].open_world:
        return registry[cls.id]
    raise KeyError(f"no term {term_id!r}; known: {', '.join(_REGISTRY)}")


def terms(open: bool = False) -> tuple[Term, ...]:
    """The registered library terms (``open``: the open-world terms): the built-in ones in the
    order defined, then the installed ones."""
    return tuple(t for t in _registry().values() if t.open_world == open)


def temperature_transform() -> Term:
    """The term that transforms the model temperature (the first registered; the built-in
    ``thermal_lag``): a model holds at most one."""
    return next(t for t in _registry().values() if t.transforms_temperature)


def is_term(term_id: str) -> bool:
    """Whether ``term_id`` is a registered term (or a further instance of an open-world one)."""
    try:
        term(term_id)
    except KeyError:
        return False
    return True


def confusable_pairs() -> dict[frozenset[str], str]:
    """``{pair of term ids: the test that would tell them apart}``, in the order declared."""
    out: dict[frozenset[str], str] = {}
    for t in _registry().values():
        for other, test in t.confusable.items():
            pair = frozenset({t.id, other})
            if pair in out:
                raise ValueError(f"confusable pair {sorted(pair)} is declared twice")
            out[pair] = test
    return out
