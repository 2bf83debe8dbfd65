"""ament_python package ``hems_ros``.

Built by colcon in a ROS 2 workspace like any ament_python package, or installed into the
project's virtual environment by ``make setup`` (see tools/ament_install.py for the ament
index entry and ``lib/hems_ros`` executables there).
"""

import runpy
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "hems_ros"
EXECUTABLES = runpy.run_path(f"{PACKAGE}/executables.py")["EXECUTABLES"]

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(include=[PACKAGE, f"{PACKAGE}.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml") + glob("config/*.xml")),
        (f"share/{PACKAGE}/config/physics", glob("config/physics/*.yaml")),
        (f"share/{PACKAGE}/config/measurements", glob("config/measurements/*")),
    ],
    # ROS packages (rclpy, the message packages) come from the ROS installation (package.xml)
    install_requires=[
        "setuptools",
        "numpy",
        "scipy",
        "threadpoolctl",
        "numba",
        "llvmlite",
        "pyyaml",
        "mcap",
        "lz4",
        "zstandard",
        "matplotlib",
        "dask",
        "distributed",
        "cloudpickle",
    ],
    extras_require={
        "test": ["pytest", "hypothesis", "rosbags", "mcap-ros2-support", "ruff", "mypy"]
    },
    zip_safe=True,
    maintainer="HEMS digital twin developers",
    description="HEMS soft hand exoskeleton digital twin (ROS 2 nodes, SMA physics, BPID control)",
    license="Apache-2.0",
    python_requires=">=3.11",
    entry_points={
        "console_scripts": [f"{name} = {target}" for name, target in EXECUTABLES.items()]
    },
)
