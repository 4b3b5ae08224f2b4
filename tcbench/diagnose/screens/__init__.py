"""The screens of a diagnosis (:mod:`~tcbench.diagnose.screens.screen`): the tests whose structure is
not an additive term of the mean model, by stage, and the order their parts take in the report.

- ``prepare``: thermometer glitches (held at the previous reading, their samples given zero
  weight) and the thermometer's quantisation, which sets the smoothing window;
- ``before`` the fit (:func:`before_fit`): the output's quantisation and saturation (clipped samples
  get zero weight), the noise level (the first variance test) and isolated outliers;
- ``after`` the final fit (:func:`after_fit`): flicker (with the recheck of the kept effects) and
  the variance of the final residual.

The tests the screens run are modules of their own: :mod:`~.glitches` (thermometer glitches),
:mod:`~.outliers` (isolated outliers), :mod:`~.saturation`, :mod:`~.quantisation` (of the output
and of the thermometer) and :mod:`~.variance` (noise whose level changes); each screen module
(:mod:`~.thermometer_glitches`, :mod:`~.thermometer`, :mod:`~.output`, :mod:`~.noise_level`,
:mod:`~.spikes`, :mod:`~.flicker`) wraps one or two of them as a :class:`~.screen.Screen`.

Each screen holds the settings it tests with (:class:`~tcbench.diagnose.settings.ScreenSettings`);
:data:`BEFORE_FIT` and :data:`AFTER_FIT` are the stages at the defaults.
"""

from __future__ import annotations

from tcbench.diagnose.screens.flicker import FlickerScreen
from tcbench.diagnose.screens.noise_level import NoiseLevelScreen, VarianceScreen
from tcbench.diagnose.screens.output import QuantisationScreen, SaturationScreen
from tcbench.diagnose.screens.screen import Screen, ScreenInput, ScreenResult, Screened, run_screens
from tcbench.diagnose.screens.spikes import OutliersScreen
from tcbench.diagnose.screens.thermometer import ThermometerScreen, smoothing
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings


def before_fit(settings: DiagnoseSettings = DEFAULTS) -> tuple[Screen, ...]:
    """The screens before the fit, in order, with ``settings``' screens section."""
    s = settings.screens
    return (QuantisationScreen(s), SaturationScreen(s), NoiseLevelScreen(s), OutliersScreen(s))


def after_fit(settings: DiagnoseSettings = DEFAULTS) -> tuple[Screen, ...]:
    """The screens after the final fit, in order, with ``settings``."""
    return (FlickerScreen(settings), VarianceScreen(settings.screens))


BEFORE_FIT: tuple[Screen, ...] = before_fit()
AFTER_FIT: tuple[Screen, ...] = after_fit()
# report.json ``effects``: after the mean model's terms, in this order
FINDINGS_ORDER = ("bias_instability", "outliers", "thermometer_glitches", "saturation", "quantisation", "thermometer_quantisation", "variance")
# model.yaml, after the fitted terms, the declared ones and the white noise: the noise's level first
# (a changing one replaces white_noise), then the converter's grid (which takes its q^2/12 out of
# the white noise), the clip levels (the final stage, as simulate applies them) and the thermometer
MODEL_ORDER = ("outliers", "variance", "quantisation", "saturation", "thermometer_quantisation")

__all__ = ["AFTER_FIT", "BEFORE_FIT", "FINDINGS_ORDER", "MODEL_ORDER", "Screen", "ScreenInput", "ScreenResult",
           "Screened", "ThermometerScreen", "after_fit", "before_fit", "run_screens", "smoothing"]
