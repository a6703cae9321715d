"""Exception types of omnikin.

Every error raised on bad input is a ``ValueError`` subclass whose message names
what is wrong and where (file, wheel, field, sample index).
"""


class OmnikinError(ValueError):
    """Base class of all omnikin input errors."""


class RobotFileError(OmnikinError):
    """A robot file (or dict) breaks schema version 1 of ``docs/conventions.md``."""


class SingularLayoutError(OmnikinError):
    """The wheel layout cannot realise or observe the motion its type promises."""


class InfeasibleTwistError(OmnikinError):
    """A commanded twist violates a no-side-slip constraint or a steering limit."""


class OdometryInputError(OmnikinError):
    """Encoder samples that cannot be integrated (time order, jumps, NaN, shape)."""
