"""Paper metrics: accelerometer, gyroscope and optimisation."""
