"""Error models: how the robot as built and its runs differ from the nominal model.

*Systematic* errors (:class:`SystematicErrors`) make a "true robot" out of the nominal one:
per wheel a relative radius error, a hub displaced by ``dx, dy`` [m] (or in polar terms,
distance and angle), a drive direction and a roller angle off by some radians, and an
encoder counting ``(1 + ticks)`` times the nominal ticks per revolution.

*Random* errors (:class:`NoiseModel`) differ from run to run:

* wheel slip: each wheel's rolling distance in a sample gets a zero-mean error of
  variance ``slip**2 * |distance|`` [slip in sqrt(m)], the distance-proportional model of
  Chong and Kleeman (1997, ref. [4] of the seed paper), so the scatter does not depend on
  the sample rate;
* floor irregularity: the heading gets a zero-mean error of variance
  ``floor**2 * |path length|`` [floor in rad/sqrt(m)] per sample;
* encoder quantisation: ticks are whole numbers (``quantise``);
* measurement: the end pose measured by hand has a zero-mean error of ``measurement`` [m]
  in x and y and ``measurement_theta`` [rad] in heading.

``PROFILES`` and ``NOISE`` hold the named profiles used by ``omnikin umbmark``; the
``typical`` as-built profile is: radius sigma 0.5 %, hub distance sigma 1 mm, hub angle and
drive direction sigma 0.5 deg (for fixed standard wheels only the hub displacement along
the axle: a toed-in or fore-aft shifted rigid wheel pair could not move at all); run-to-run
return scatter of about 10 mm on the 4 m square;
end-pose measurement sigma 1 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..common.messages import did_you_mean, shorten
from ..errors import InputError
from ..kinematics.robot import Robot


@dataclass(frozen=True)
class WheelErrors:
    """Systematic errors of one wheel (true = nominal + error)."""

    radius: float = 0.0  # relative: r_true = r (1 + radius)
    dx: float = 0.0  # hub displacement [m], body frame
    dy: float = 0.0
    drive: float = 0.0  # drive direction error [rad]
    roller: float = 0.0  # roller angle error [rad] (Swedish wheels)
    ticks: float = 0.0  # relative: ticks_per_rev_true = ticks_per_rev (1 + ticks)

    def __post_init__(self):
        for name in ("radius", "dx", "dy", "drive", "roller", "ticks"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"WheelErrors.{name} must be a finite number, got {v!r}")
        if self.radius <= -1 or self.ticks <= -1:
            raise InputError("WheelErrors.radius and .ticks are relative errors and must be > -1")


@dataclass(frozen=True)
class SystematicErrors:
    """Per-wheel systematic errors, keyed by wheel name."""

    wheels: dict

    def __post_init__(self):
        object.__setattr__(self, "wheels", dict(self.wheels))

    def apply(self, robot: Robot) -> Robot:
        """The true robot: ``robot`` with these errors built in. Everything the errors do not
        change is kept (each wheel's encoder ``gear_ratio``, ``invert``, ``counter_bits``, its
        ``max_speed``, ``steer``, ``motor`` and physical fields; the robot's description,
        references and physical fields), and the robot remembers its design
        (:attr:`omnikin.kinematics.robot.Robot.design`: ``robot``, or ``robot``'s own design), from which a
        physics description takes its body and a dc motor's controller its encoder scale."""
        unknown = sorted(set(self.wheels) - {w.name for w in robot.wheels})
        if unknown:
            raise InputError(f"errors name wheels {unknown} that robot {robot.name!r} does not have")
        wheels = []
        for w in robot.wheels:
            e = self.wheels.get(w.name, WheelErrors())
            enc = w.encoder
            if enc is not None and e.ticks:
                enc = replace(enc, ticks_per_rev=enc.ticks_per_rev * (1 + e.ticks))
            roller = w.roller + e.roller if w.is_swedish and w.type != "omni" else w.roller
            if w.type == "omni" and e.roller:
                # an omni wheel with a roller error is a Swedish wheel of that small angle
                w = replace(w, type="swedish")
                roller = e.roller
            wheels.append(
                replace(
                    w,
                    x=w.x + e.dx,
                    y=w.y + e.dy,
                    drive=w.drive + e.drive,
                    roller=roller,
                    radius=w.radius * (1 + e.radius),
                    encoder=enc,
                )
            )
        if all(not any(vars(e).values()) for e in self.wheels.values()):
            return robot  # built exactly as designed (--errors none): the robot itself, by its name
        design = robot.design if robot.design is not None else robot
        return replace(robot, name=f"{robot.name} (as built)", wheels=tuple(wheels), design=design)

    def as_dict(self) -> dict:
        return {
            name: {k: float(getattr(e, k)) for k in ("radius", "dx", "dy", "drive", "roller", "ticks")}
            for name, e in self.wheels.items()
        }


@dataclass(frozen=True)
class ErrorProfile:
    """Standard deviations of the systematic errors drawn by :meth:`sample`."""

    radius: float = 0.0  # relative
    distance: float = 0.0  # m, radial hub displacement
    angle: float = 0.0  # rad, hub displacement along the circle through it
    drive: float = 0.0  # rad
    roller: float = 0.0  # rad
    ticks: float = 0.0  # relative
    hub: float = 0.0  # m, hub displacement in any direction (isotropic, each of x and y)

    def sample(self, robot: Robot, rng) -> SystematicErrors:
        """Draw one robot's worth of errors (``rng``: a numpy Generator or a seed).

        Per wheel six standard normals ``z`` in a fixed order (radius, radial, tangential, drive,
        roller, ticks), whatever the profile, so that two profiles sampled from the same seed
        draw the same build scaled: radius ``radius z0``; hub moved ``(distance + hub) z1``
        radially and ``(d angle + hub) z2`` along the circle of radius ``d`` through it (``hub``
        thus an isotropic displacement of sigma ``hub`` in x and in y); drive ``drive z3``;
        roller ``roller z4``; ticks ``ticks z5``."""
        rng = np.random.default_rng(rng)
        out = {}
        for w in robot.wheels:
            z = rng.standard_normal(6)
            dist = math.hypot(w.x, w.y)
            beta = math.atan2(w.y, w.x)
            dr = (self.distance + self.hub) * z[1]
            dt = (dist * self.angle + self.hub) * z[2]  # along the circle [m]
            dx = dr * math.cos(beta) - dt * math.sin(beta)
            dy = dr * math.sin(beta) + dt * math.cos(beta)
            drive = self.drive * z[3]
            if w.is_fixed:
                # rigid fixed wheels that are toed in or not coaxial admit no motion: keep only
                # the displacement along the axle (the track error) and the radius error
                along = -math.sin(w.drive) * dx + math.cos(w.drive) * dy
                dx, dy, drive = -math.sin(w.drive) * along, math.cos(w.drive) * along, 0.0
            out[w.name] = WheelErrors(
                radius=self.radius * z[0],
                dx=dx,
                dy=dy,
                drive=drive,
                roller=self.roller * z[4] if w.is_swedish else 0.0,
                ticks=self.ticks * z[5] if w.encoder is not None else 0.0,
            )
        return SystematicErrors(out)


@dataclass(frozen=True)
class NoiseModel:
    """Random errors of a run (module docstring)."""

    slip: float = 0.0  # sqrt(m)
    floor: float = 0.0  # rad / sqrt(m)
    quantise: bool = True
    measurement: float = 0.0  # m
    measurement_theta: float = 0.0  # rad

    def __post_init__(self):
        for name in ("slip", "floor", "measurement", "measurement_theta"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise InputError(f"NoiseModel.{name} must be a finite number >= 0, got {v!r}")

    @property
    def is_zero(self) -> bool:
        return self.slip == 0 and self.floor == 0


PROFILES = {
    "typical": ErrorProfile(radius=0.005, distance=0.001, angle=math.radians(0.5), drive=math.radians(0.5)),
    "none": ErrorProfile(),
}
"""Systematic error profiles by name (``--errors``)."""

NOISE = {
    "typical": NoiseModel(slip=2e-4, floor=1e-4, measurement=0.001, measurement_theta=math.radians(0.2)),
    "none": NoiseModel(quantise=False),
}
"""Random error models by name (``--noise``)."""


def error_profile(name: str) -> ErrorProfile:
    """The systematic error profile called ``name`` (:data:`PROFILES`)."""
    if not isinstance(name, str) or name not in PROFILES:
        raise InputError(
            f"unknown error profile {shorten(name)}{did_you_mean(name, PROFILES)}; one of {sorted(PROFILES)}"
        )
    return PROFILES[name]


def noise_profile(name: str) -> NoiseModel:
    """The random error model called ``name`` (:data:`NOISE`)."""
    if not isinstance(name, str) or name not in NOISE:
        raise InputError(f"unknown noise profile {shorten(name)}{did_you_mean(name, NOISE)}; one of {sorted(NOISE)}")
    return NOISE[name]
