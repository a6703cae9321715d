"""The 3D viewer of ``omnikin view`` (extra ``viewer``): the robot in the browser, drawn with viser
from its physical description, driven from the page's keyboard and controls through the runtime.

Modules: :mod:`.scene` (the robot's nodes and the world around it), :mod:`.live` (engine and
runtime behind the page), :mod:`.panel` (controls, readouts, plots), :mod:`.front` (the server on
the user's address: page, keys, relay to viser), :mod:`.app` (all of it together).
"""
