"""The 3D viewer of ``omnikin view`` (extra ``viewer``): the robot in the browser, drawn with viser
from its physical description, driven from the page's keyboard and controls through the runtime,
or a recorded run played back.

Modules: :mod:`.scene` (the robot's nodes and the world around it), :mod:`.live` (engine and
runtime behind the page), :mod:`.panel` (controls, readouts, plots), :mod:`.front` (the server on
the user's address: page, keys, relay to viser), :mod:`.serving` (both servers together),
:mod:`.app` (the live page), :mod:`.replay`, :mod:`.replay_sources` and :mod:`.replay_page` (a
report's runs or a bag played back).
"""
