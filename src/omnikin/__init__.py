"""omnikin: kinematics, exact odometry and UMBmark for wheeled mobile robots.

Layers (each imports only those above it in this list): ``geometry`` -> ``wheels``
-> ``model`` (with ``mobility``) -> ``presets`` -> ``odometry`` (with ``encoders``
and ``integration``). Edges: ``io``, ``viz``, ``cli``.
"""

from .errors import (InfeasibleTwistError, InputError, LinkError, OdometryInputError, OmnikinError,
                     RobotFileError, SingularLayoutError)
from .model import FKResult, IKResult, Robot
from .odometry import OdometryResult, batch_odometry, batch_odometry_from_angles
from .streaming import Odometry
from .presets import PRESET_NAMES
from .wheels import Encoder, Steer, Wheel

__version__ = "0.1.0"


def load_robot(spec):
    """Load a robot from a preset name or a robot file (YAML or JSON)."""
    from .io.robot_file import load_robot as _load

    return _load(spec)


__all__ = [
    "Encoder", "FKResult", "IKResult", "InfeasibleTwistError", "InputError", "LinkError", "Odometry", "OdometryInputError",
    "OdometryResult", "OmnikinError", "PRESET_NAMES", "Robot", "RobotFileError", "SingularLayoutError",
    "Steer", "Wheel", "batch_odometry", "batch_odometry_from_angles", "load_robot", "__version__",
]
