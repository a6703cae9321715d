"""What the sensors a robot carries read (``docs/sensors.md``): a lidar's scan of a world
(:mod:`~omnikin.sensors.lidar`) and an IMU's readings from the true motion
(:mod:`~omnikin.sensors.imu`), their errors drawn from the run's seed."""
