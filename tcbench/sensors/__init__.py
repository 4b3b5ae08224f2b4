"""Sensor simulators, test protocols and recordings."""
