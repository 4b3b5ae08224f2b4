"""The screens of a diagnosis (:mod:`~tcbench.diagnose.screens.base`): the tests whose structure is
not an additive term of the mean model, by stage, and the order their parts take in the report.

- ``prepare``: the thermometer's quantisation, which sets the smoothing window;
- ``before`` the fit (:data:`BEFORE_FIT`): the output's quantisation and saturation (clipped samples
  get zero weight), the noise level (the first variance test) and isolated outliers;
- ``after`` the final fit (:data:`AFTER_FIT`): flicker (with the recheck of the kept effects) and
  the variance of the final residual.
"""

from __future__ import annotations

from tcbench.diagnose.screens.base import Screen, ScreenInput, ScreenResult, Screened, run_screens
from tcbench.diagnose.screens.flicker import FlickerScreen
from tcbench.diagnose.screens.outliers import OutliersScreen
from tcbench.diagnose.screens.output import QuantisationScreen, SaturationScreen
from tcbench.diagnose.screens.thermometer import ThermometerScreen, smoothing
from tcbench.diagnose.screens.variance import NoiseLevelScreen, VarianceScreen

BEFORE_FIT: tuple[Screen, ...] = (QuantisationScreen(), SaturationScreen(), NoiseLevelScreen(), OutliersScreen())
AFTER_FIT: tuple[Screen, ...] = (FlickerScreen(), VarianceScreen())
# report.json ``effects``: after the mean model's terms, in this order
FINDINGS_ORDER = ("bias_instability", "outliers", "saturation", "quantisation", "thermometer_quantisation", "variance")
# model.yaml, after the fitted terms, the declared ones and the white noise: the noise's level first
# (a changing one replaces white_noise), then the converter's grid (which takes its q^2/12 out of
# the white noise), the clip levels (the final stage, as simulate applies them) and the thermometer
MODEL_ORDER = ("outliers", "variance", "quantisation", "saturation", "thermometer_quantisation")

__all__ = ["AFTER_FIT", "BEFORE_FIT", "FINDINGS_ORDER", "MODEL_ORDER", "Screen", "ScreenInput", "ScreenResult",
           "Screened", "ThermometerScreen", "run_screens", "smoothing"]
