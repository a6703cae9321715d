"""Robot runtime, free of ROS: base controller, wheel back-ends, serial protocol.

The ROS 2 node (:mod:`omnikin.ros`) is a thin shell around :class:`~.base.BaseRuntime`.
"""
