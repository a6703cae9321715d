"""The points of a tolerance study and the seed of each of their trials.

A *point* (:class:`Point`) is one setting of every factor of ``omnikin sweep``: a robot, its
build tolerances (a ``scale`` times the standard deviations ``radius`` [relative], ``hub``
[m, isotropic hub displacement] and ``drive_deg`` [deg]), the random errors of its runs
(``noise``, a profile of :data:`~omnikin.simulation.error_models.NOISE`; kinematic engine
only), its encoders' resolution (``ticks_per_rev``; None keeps the robot's), the sample
``rate`` [Hz], whether it calibrates, the ``engine`` and the UMBmark square (``side`` [m],
``mode``, ``runs`` per direction). A point is named by :func:`point_key`, a hash of its
settings (and of its robot's content), not by its place in the grid: extending or reordering
a grid keeps the results already computed.

Seeds (:func:`trial_seed`): trial ``k`` of every point of one robot draws from
``SeedSequence(seed, spawn_key=(robot words..., k))``; the tolerances, noise and other factors
are left out of the key on purpose (*common random numbers*): trial ``k`` of two tolerance
points is the same build scaled (:meth:`~omnikin.simulation.error_models.ErrorProfile.sample`
draws the same normals whatever the profile), so curves of the error against the tolerance are
smooth and the differences between points are sharp; each point's own statistics are those of
independent trials. A trial's result depends on nothing else: not on the worker, the task it
ran in, nor the order in which trials finish.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from ..evaluation.tolerance_trial import TrialSettings
from ..kinematics.robot import Robot
from ..motion.plans import UMBMARK_SIDE
from ..physics.engines import engine_named
from ..simulation.error_models import NOISE, ErrorProfile

TOLERANCE_FACTORS = ("scale", "radius", "hub", "drive_deg")
"""The factors that set a point's build tolerances (their product with ``scale``)."""


@dataclass(frozen=True)
class Point:
    """One setting of every factor of a study (module docstring). ``robot`` is the robot as the
    study names it (a preset name or a file path as written), ``robot_hash`` the hash of its
    content (:func:`robot_hash`)."""

    robot: str
    robot_hash: str
    scale: float = 1.0
    radius: float = 0.005
    hub: float = 0.001
    drive_deg: float = 0.5
    noise: str | None = "typical"
    ticks_per_rev: int | None = None
    rate: float = 100.0
    calibrate: bool = True
    engine: str = "kinematic"
    side: float = UMBMARK_SIDE
    mode: str = "rotate"
    runs: int = 5

    @property
    def tolerances(self) -> ErrorProfile:
        """The standard deviations the robot is built within: ``scale`` times radius, hub, drive."""
        return ErrorProfile(
            radius=self.scale * self.radius,
            hub=self.scale * self.hub,
            drive=math.radians(self.scale * self.drive_deg),
        )

    @property
    def settings(self) -> TrialSettings:
        """How this point's trials run UMBmark (:class:`~omnikin.evaluation.tolerance_trial.TrialSettings`)."""
        return TrialSettings(
            side=self.side,
            mode=self.mode,
            runs=self.runs,
            rate=self.rate,
            noise=NOISE[self.noise] if self.noise is not None else NOISE["none"],
            calibrate=self.calibrate,
            engine=engine_named(self.engine),  # the point stores the name (a table column)
        )

    def robot_for(self, robot: Robot) -> Robot:
        """``robot`` with this point's encoder resolution (every encoder counts ``ticks_per_rev``)."""
        if self.ticks_per_rev is None:
            return robot
        wheels = tuple(
            replace(w, encoder=replace(w.encoder, ticks_per_rev=float(self.ticks_per_rev)))
            if w.encoder is not None
            else w
            for w in robot.wheels
        )
        return replace(robot, wheels=wheels)

    def as_dict(self) -> dict:
        return asdict(self)


POINT_FIELDS = tuple(f.name for f in fields(Point))
"""The settings of a point in their order (the first columns of the study's tables)."""


def canonical_json(value) -> str:
    """``value`` as JSON with sorted keys and no spaces: the same text for the same value."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def robot_hash(robot: Robot) -> str:
    """A 16-hex-digit hash of ``robot``'s content (its robot file dict), whatever its name or file."""
    from ..io.robot_file import robot_to_dict

    return _digest(canonical_json(robot_to_dict(robot)))


def point_key(point: Point) -> str:
    """The name of ``point``: a 16-hex-digit hash of all its settings (module docstring)."""
    return _digest(canonical_json(point.as_dict()))


def trial_seed(seed: int, point: Point, trial: int) -> np.random.SeedSequence:
    """The seed of trial ``trial`` (0-based) of ``point`` in a study of seed ``seed`` (module
    docstring: common random numbers across the points of one robot)."""
    words = (int(point.robot_hash[:8], 16), int(point.robot_hash[8:16], 16))
    return np.random.SeedSequence(seed, spawn_key=(*words, trial))


def result_versions() -> dict[str, str]:
    """The versions a trial's numbers depend on besides its seed: omnikin's and NumPy's (a study
    folder and a cluster's workers must agree on them)."""
    from .._version import __version__

    return {"omnikin": __version__, "numpy": np.__version__}
