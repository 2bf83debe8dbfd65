"""Plain-Python logic of the HEMS node graph (no rclpy): names, setpoint rules, the
supervisor's state machine and monitors, a unit's driver, a finger's control loop, the
injected sensor faults, the pulley transmission. Node shells in :mod:`hems_ros.nodes` wire
these to topics and timers."""
