"""Bags: MCAP in the rosbag2 layout, written and read without ROS (no rclpy here).

- :class:`BagWriter` writes serialized messages as received into ``<folder>/<folder>_0.mcap``
  and ``metadata.yaml``;
- :func:`load_bag` decodes topics into numpy columns, :func:`iter_messages` yields them raw,
  :func:`bag_info` counts them; all three read unfinished and cut files as far as they go;
- :mod:`hems_ros.bag.recording` runs the recorder node as a child process.
"""

from hems_ros.bag.mcapscan import BagFormatError, ScanReport
from hems_ros.bag.reader import (
    Bag,
    BagInfo,
    BagWarning,
    RawMessage,
    TopicData,
    bag_files,
    bag_info,
    iter_messages,
    load_bag,
)
from hems_ros.bag.selection import DEFAULT_RECORD_REGEX, TopicSelection
from hems_ros.bag.writer import BagSummary, BagWriter, offered_lease_ns, offered_qos

__all__ = [
    "DEFAULT_RECORD_REGEX",
    "Bag",
    "BagFormatError",
    "BagInfo",
    "BagSummary",
    "BagWarning",
    "BagWriter",
    "RawMessage",
    "ScanReport",
    "TopicData",
    "TopicSelection",
    "bag_files",
    "bag_info",
    "iter_messages",
    "load_bag",
    "offered_lease_ns",
    "offered_qos",
]
