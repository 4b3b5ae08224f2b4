"""Seed 001's dual-mass vibratory gyroscope: output the rate in deg/s."""

from tcbench.sensors import protocols
from tcbench.sensors.devices import gyro_power_on, gyro_unit
from tcbench.sensors.kinds import SensorKind

KIND = SensorKind(
    name="gyro",
    title="MEMS vibratory gyroscope (output a rate)",
    input_unit="deg/s",
    output_unit="deg/s",
    input_field="rate_dps",
    input_range=(-20000.0, 20000.0),  # MEMS gyros measure up to a few thousand deg/s
    output_range=(-20000.0, 20000.0),
    device=gyro_unit,
    power_on=gyro_power_on,
    protocols={"oven": protocols.gyro_oven, "static": protocols.gyro_static},
    noise_unit="°/h",
    noise_scale=3600.0,
    ulog_topic="sensor_gyro",
    ulog_unit="rad/s",
    px4_letter="G",
)
