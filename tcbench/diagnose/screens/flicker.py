"""Flicker (``bias_instability``): the Allan test of the final model's in-sample residual against
white noise plus the thermometer noise the model inherits, and the recheck of the kept effects
with that flicker in the noise model.

Deterministic before stochastic: while the physics-agnostic reference beats the final model by
more than its ``structure_ratio``, an Allan excess is the structure
the model leaves, not flicker; and the recheck may not hand flicker structure the reference
shows. The Allan test reads the in-sample residual: a held-out one carries each fold's
coefficient error, constant over its blocks, which looks like slow noise. The test's
false-alarm probability is :class:`~tcbench.diagnose.settings.FlickerSettings`; the recheck takes
each kept effect's score variance under the flicker found exactly (no draws, so no seed), drops
the weakest first and measures the flicker again after each drop.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.result import Confusion, rmse
from tcbench.diagnose.screens.screen import AFTER, Screen, ScreenInput, ScreenResult
from tcbench.diagnose.select.attribute import Attribution, recheck_with_flicker
from tcbench.diagnose.select.crossval import Fit
from tcbench.diagnose.select.design import Model
from tcbench.diagnose.select.evidence import Evidence
from tcbench.diagnose.select.library_findings import Extent, library_finding
from tcbench.diagnose.select.locate import AllanExcess, allan_excess, why_no_allan
from tcbench.diagnose.select.reference import Reference
from tcbench.diagnose.select.thermometer_noise import propagated_noise
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings
from tcbench.diagnose.terms import terms

ID = "bias_instability"
FLICKER_FLOOR = 0.664  # Allan floor of flicker noise per unit b
FLICKER_TEST = ("a second power-on or a longer run: warm-up repeats after every power-on and ageing keeps "
                "its sign, a flicker excursion does neither")


def time_effects() -> tuple[str, ...]:
    """The library terms a slow random excursion of the bias can mimic (registered now)."""
    return tuple(t.id for t in terms() if t.flicker_mimics)


@dataclass(frozen=True)
class Flicker(ScreenResult):
    """The Allan test of one fit's residual (None where the record allows none) and the flicker
    coefficient ``b`` when it flattens above the white (plus thermometer) line and is not the
    structure the model leaves; ``declared`` whether the starting model has it already;
    ``attribution`` the final model after the recheck, where it dropped effects."""

    allan: AllanExcess | None
    b: float | None
    extent: Extent
    declared: bool = False
    attribution: Attribution | None = None

    @property
    def named(self) -> bool:
        """Whether the diagnosis names flicker as found."""
        return self.b is not None and not self.declared

    def evidence(self) -> Evidence:
        """How ``bias_instability`` fared; for a kept one ``gain`` is the Allan ratio at the
        first flagged tau and ``threshold`` its bound."""
        if self.declared:
            return Evidence(ID, "in the model", reason="declared in the starting model")
        allan = self.allan
        if allan is None:
            return Evidence(ID, "not identifiable", reason="no Allan deviation on this record")
        if self.b is None or allan.first_over is None:
            return Evidence(ID, "rejected", reason="the residual's Allan deviation follows the white-noise line")
        k = allan.first_over
        return Evidence(ID, "kept", float(allan.adev[k] / allan.white[k]), float(allan.bound[k]),
                        reason=f"Allan deviation above the white line from tau = {allan.tau_s[k]:.4g} s")

    def findings(self, unit: str) -> list[Finding]:
        if not self.named:
            return []
        ev = self.evidence()
        tau_s = float(self.allan.tau_s[self.allan.first_over])  # type: ignore[union-attr,index]
        return [library_finding(ID, {"b": self.b}, {"allan_ratio": ev.gain, "bound": ev.threshold, "tau_s": tau_s},
                                self.extent)]

    def write_model(self, model: dict[str, Any]) -> None:
        if self.named:
            model["effects"][ID] = {"b": self.b}

    def confusions(self, found: list[str]) -> list[Confusion]:
        """The effects found that a slow random excursion of the bias can mimic."""
        return [Confusion((e, ID), FLICKER_TEST) for e in found if e in time_effects()] if self.named else []


def flicker_test(att: Attribution, fit: Fit, model: Model,
                 false_alarm: float = DEFAULTS.screens.flicker.false_alarm,
                 min_samples: int = DEFAULTS.locate.min_allan_samples) -> tuple[AllanExcess | None, float | None]:
    """Allan test of the in-sample residual of ``fit`` (of ``model``) against white noise plus the
    thermometer noise the model inherits, at ``false_alarm`` from a tau of ``min_samples``
    samples; the flicker coefficient ``b`` when it flattens above both."""
    designer = att.designer
    data = designer.data
    thermometer = propagated_noise(designer, model, fit.beta)
    ex = allan_excess(data.t_s, fit.residual, data.white_sigma, false_alarm, estimated=True, coloured=thermometer,
                      min_samples=min_samples)
    if ex is None or ex.first_over is None:
        return ex, None
    excess = np.sqrt(np.maximum(ex.adev**2 - ex.white**2, 0.0))
    return ex, float(excess[ex.first_over:].max() / FLICKER_FLOOR)


def final_rmse(att: Attribution) -> float:
    """The held-out RMSE of the final model of ``att`` (output unit)."""
    return rmse(att.final_fit.sse_heldout, att.designer.data.n)


@dataclass(frozen=True)
class FlickerScreen(Screen):
    """The Allan test of the final residual; when it finds flicker behind kept effects, they are
    tested again with that flicker in the noise model, the weakest dropped first and the flicker
    measured again on what remains after each drop, never past where the reference shows
    deterministic structure (:func:`~tcbench.diagnose.select.attribute.recheck_with_flicker`); the test
    is run again on what remains (``settings.screens.flicker``, its shortest tau
    ``settings.locate.min_allan_samples``), and the flicker it names is the one the kept effects
    were judged against."""

    settings: DiagnoseSettings = DEFAULTS
    id = ID
    stage = AFTER

    def skip(self, given: ScreenInput) -> str | None:
        return why_no_allan(given.data.t_s, self.settings.locate.min_allan_samples)  # type: ignore[union-attr]

    def test(self, att: Attribution) -> tuple[AllanExcess | None, float | None]:
        """:func:`flicker_test` of the final model of ``att``."""
        return flicker_test(att, att.final_fit, att.final, self.settings.screens.flicker.false_alarm,
                            self.settings.locate.min_allan_samples)

    def run(self, given: ScreenInput) -> Flicker:
        att, reference = given.attribution, given.reference
        assert att is not None and reference is not None
        allan, b = self.test(att)
        found = Flicker(allan, b, Extent.of(att.designer.data), ID in given.declared)
        if reference.structure_remains(final_rmse(att)):  # an Allan excess made by it is not flicker
            return replace(found, b=None)
        if found.b is None or len(att.final.ids) <= len(att.base.ids):
            return found
        settings = self.settings

        def flicker_of(model: Model, fit: Fit) -> float | None:
            return flicker_test(att, fit, model, settings.screens.flicker.false_alarm,
                                settings.locate.min_allan_samples)[1]

        rechecked = recheck_with_flicker(att, found.b, flicker_of, reference.structure_remains)
        if rechecked is att or reference.structure_remains(final_rmse(rechecked)):
            return found
        allan, b = self.test(rechecked)
        return replace(found, allan=allan, b=b, attribution=rechecked)


def flicker_evidence(found: ScreenResult | None, skipped: str | None, declared: bool, reference: Reference,
                     final: float, unit: str) -> Evidence:
    """How ``bias_instability`` fared: as the screen's result says, or not identifiable where the
    screen was skipped; not tested while deterministic structure remains (the final model's
    held-out RMSE ``final`` above the ``reference``'s ratio): flicker is judged only once that
    structure is modelled."""
    if declared:
        return Evidence(ID, "in the model", reason="declared in the starting model")
    if reference.structure_remains(final):
        return Evidence(ID, "not tested", reason=(
            f"deterministic temperature structure remains (the reference reaches {reference.rmse_heldout:.4g}, "
            f"the final model {final:.4g} {unit} held out): flicker is judged only once it is modelled"))
    if isinstance(found, Flicker):
        return found.evidence()
    return Evidence(ID, "not identifiable", reason=skipped or "no Allan deviation on this record")
