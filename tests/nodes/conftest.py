"""Fixtures of the node tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def context(ros_domain_id):
    """An rclpy context of its own for in-process nodes, shut down after the test."""
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context)
    yield context
    rclpy.shutdown(context=context)
