"""What a ``/diagnostics`` status of the omnikin node says once nothing is wrong with the robot.

On a busy machine the node's status may warn of its own pace (``<n> control cycle(s) overran
the period``, ``simulation <s> s behind real time``: :func:`omnikin.ros.messages.diagnostic_status`,
rule 4) while the robot is fine; a test that waits for the robot to recover accepts those
parts and nothing else.
"""

from __future__ import annotations

PACE_PARTS = ("control cycle(s) overran the period", "s behind real time")
"""The endings of the parts of a WARN message that report only the machine's pace."""


def pace_only(message: str) -> bool:
    """True when every ``; ``-separated part of ``message`` reports only the machine's pace."""
    return all(part.endswith(PACE_PARTS) for part in message.split("; "))


def running(status) -> bool:
    """True for a ``diagnostic_msgs/DiagnosticStatus`` that reports a robot with nothing wrong:
    OK ``running``, or WARN about the machine's pace only."""
    from diagnostic_msgs.msg import DiagnosticStatus

    if status.level == DiagnosticStatus.OK:
        return True
    return status.level == DiagnosticStatus.WARN and pace_only(status.message)
