"""Seed 000's micro-silicon resonant accelerometer: output the resonators' frequency difference in Hz."""

from tcbench.sensors import protocols
from tcbench.sensors.devices import msra_power_on, msra_unit
from tcbench.sensors.kinds import SensorKind

KIND = SensorKind(
    name="msra",
    title="resonant accelerometer (MSRA, output a frequency difference)",
    input_unit="g",
    output_unit="Hz",
    input_field="accel_g",
    input_range=(-1000.0, 1000.0),  # accelerometers measure up to a few hundred g
    output_range=(-1.0e6, 1.0e6),  # a frequency difference well below the ~30 kHz resonance
    device=msra_unit,
    power_on=msra_power_on,
    protocols={"roomtemp": protocols.msra_roomtemp, "fulltemp": protocols.msra_fulltemp},
    default_protocol="fulltemp",  # the paper's full-temperature test
    positions=True,
    noise_unit="µg",
    noise_scale=float("nan"),  # Hz -> µg needs the device's scale factor (metrics read it from the sidecar)
)
