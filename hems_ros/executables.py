"""The package's executables: name -> console entry point.

Read by setup.py (console scripts on PATH) and by tools/ament_install.py (the same
executables in ``<prefix>/lib/hems_ros`` where ``ros2 run`` looks). Kept free of imports so
that both can load it without importing rclpy.
"""

EXECUTABLES = {
    "hems": "hems_ros.cli.main:main",
    "ping_responder": "hems_ros.nodes.ping_responder:main",
    "recorder": "hems_ros.nodes.recorder:main",
    "actuation_unit": "hems_ros.nodes.actuation_unit:main",
    "shoulder_module": "hems_ros.nodes.shoulder_module:main",
    "finger_controller": "hems_ros.nodes.finger_controller:main",
    "supervisor": "hems_ros.nodes.supervisor:main",
}
