"""ROS 2 message definitions and their CDR encoding, in plain Python (no rclpy here).

The nodes' hot path and the bag reader and writer share it: :mod:`hems_ros.codec.msgdefs`
parses ``.msg`` definitions, :mod:`hems_ros.codec.cdr` builds encoders and decoders from them.
"""
