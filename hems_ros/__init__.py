"""HEMS digital twin: SMA actuation-unit physics, BPID control and the ROS 2 node graph."""

__version__ = "0.1.0"
