"""The world around a robot (``docs/world.md``): what it holds (:mod:`~omnikin.world.model`),
its plane shapes, distances and ray casts (:mod:`~omnikin.world.shapes`), and a robot's
footprint meeting them (:mod:`~omnikin.world.collision`)."""

from .collision import Contact, Footprint
from .model import Box, Cylinder, Floor, Mark, Patch, Wall, World, make_world

__all__ = ["Box", "Contact", "Cylinder", "Floor", "Footprint", "Mark", "Patch", "Wall", "World", "make_world"]
