"""``omnikin.simulate``: one simulated run, as ``omnikin simulate`` makes it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..model import Robot
from ..resource_limits import DEFAULT_MEMORY, DEFAULT_TIME
from ..simulation.error_models import SystematicErrors
from ..simulation.simulate import SimulatedRun
from .common import as_built, noise_of, require_viz, robot_of

DEFAULT_PATH = "square cw rotate 4"
"""The path of ``omnikin simulate`` without ``--path``."""


@dataclass(frozen=True)
class Simulation:
    """A simulated run (:func:`simulate`): ``run`` holds the times [s], encoder ticks, odometry,
    ground truth and measured end pose (:class:`~omnikin.simulation.simulate.SimulatedRun`);
    ``injected`` the systematic errors drawn (None for a given true robot)."""

    robot: Robot
    true_robot: Robot
    injected: SystematicErrors | None
    path: str
    run: SimulatedRun

    @property
    def end_error(self) -> np.ndarray:
        """True end pose minus odometry end pose ``(x [m], y [m], theta [rad])``."""
        from ..geometry import wrap_angle

        d = self.run.truth[0, -1] - self.run.odometry[-1]
        d[2] = wrap_angle(d[2])
        return d

    def plot(self):
        """True path and odometry [m] (a matplotlib ``Figure``)."""
        require_viz()
        from ..viz.runs import run_figure

        return run_figure(self.run, f"{self.robot.name}: {self.path}")


@dataclass(frozen=True)
class SimulationCost:
    """What a run of :func:`simulate` is estimated to cost, before it starts (its ``on_cost``).

    ``samples``: samples of the plan at the rate (an upper bound,
    :func:`~omnikin.simulation.simulate.run_cost`); ``memory`` [bytes]: the run's arrays for those
    samples; ``duration`` [s]: the simulated time; ``seconds`` [s]: the wall time. The physics
    engine is estimated in two steps: first before the plan is sampled (``memory`` with room for
    the longest tail the run may add after the plan, ``duration`` and ``seconds`` None), then
    with its model built and timed (``duration``: the run's, its steering waits and its tail at
    their limits; ``memory``: the plan's samples alone).
    """

    samples: float
    memory: float
    duration: float | None
    seconds: float | None


def simulate(
    robot,
    path=DEFAULT_PATH,
    *,
    true_robot=None,
    errors="typical",
    noise=None,
    seed: int = 1,
    rate: float = 100.0,
    engine: str = "kinematic",
    step: float | None = None,
    max_memory: float = DEFAULT_MEMORY,
    max_time: float = DEFAULT_TIME,
    progress: Callable[[float, float], None] | None = None,
    on_cost: Callable[[SimulationCost], None] | None = None,
) -> Simulation:
    """Simulate ``robot`` as built driving ``path`` commanded by its nominal model
    (``omnikin simulate``, without the bag).

    ``path``: a :class:`~omnikin.plans.Plan` (plans add: ``line(4) + spin(math.pi)``) or a path
    in the runs-file grammar (:func:`omnikin.plans.parse_plan`); ``true_robot`` (robot file or
    Robot) replaces the seeded draw of the
    ``errors`` profile; ``noise``: random errors (profile name or
    :class:`~omnikin.simulation.error_models.NoiseModel`; default ``"typical"``); ``rate`` [Hz], within
    :data:`~omnikin.simulation.motion.RATE_RANGE` as for ``omnikin simulate``. The seed's first
    stream draws the robot as built (the same robot as ``omnikin umbmark --seed``), its second
    the run, as ``omnikin simulate`` does. A run estimated to need more than ``max_memory``
    [bytes] or ``max_time`` [s] is refused before it starts
    (:func:`~omnikin.simulation.simulate.run_cost`, the estimate ``omnikin simulate`` checks
    against ``--max-memory`` and ``--max-time``).

    ``engine="physics"`` drives the robot as built in MuJoCo instead
    (:func:`omnikin.physics.run.simulate_physics`, ``omnikin simulate --engine physics``) at
    time step ``step`` [s] (default 2 ms): the same plan, rate and robot as built; ``noise``
    must then be left out (the physics has no random error model). ``progress``, if given, is
    called now and then with the simulated time and the plan's duration [s] (physics only).

    ``on_cost``, if given, is called with each estimate (:class:`SimulationCost`) before this
    function checks it against ``max_memory`` and ``max_time`` (``omnikin simulate`` checks it
    against its options, with the time of writing its outputs, and the stamps its outputs can
    hold); it may raise to refuse the run.
    """
    from ..evaluation.physics_study import engine_options
    from ..evaluation.procedure import ARGUMENTS, streams
    from ..plans import Plan, parse_plan
    from ..resource_limits import require_within
    from ..simulation.motion import check_rate_range
    from ..simulation.simulate import run_cost
    from ..simulation.simulate import simulate as simulate_run

    check_rate_range(rate, "rate")
    noise, step = engine_options(engine, noise, step)
    nominal = robot_of(robot)
    plan = path if isinstance(path, Plan) else parse_plan(str(path))
    cost = run_cost(plan, nominal, rate)
    seeds = list(streams(seed).values())
    true, injected = as_built(nominal, true_robot, errors, seeds[0])

    def within(**estimate) -> None:  # memory, seconds and what to change: refused beyond the limits
        size = f"{cost.samples:.3g} samples"
        require_within("simulate", max_memory=max_memory, max_time=max_time, names=ARGUMENTS, size=size, **estimate)

    def told(estimate: SimulationCost) -> None:
        if on_cost is not None:
            on_cost(estimate)

    if engine == "physics":
        from ..physics.cost import physics_run_cost
        from ..physics.run import TAIL_MAX, simulate_physics
        from ..simulation.motion import sample_plan

        assert step is not None
        tail = cost.bytes / max(cost.samples, 1.0) * TAIL_MAX * rate
        told(SimulationCost(cost.samples, cost.bytes + tail, None, None))
        within(memory=cost.bytes + tail, hint="lower rate or shorten path")
        sampled = sample_plan(plan, nominal, rate)
        estimate = physics_run_cost(sampled, true, nominal, step, budget=max_time)
        told(SimulationCost(cost.samples, cost.bytes, estimate.simulated, estimate.seconds))
        within(seconds=estimate.seconds, hint="shorten path or raise step")
        run: SimulatedRun = simulate_physics(sampled, true, nominal, rate=rate, step=step, progress=progress)
    else:
        told(SimulationCost(cost.samples, cost.bytes, cost.samples / rate, cost.seconds))
        within(memory=cost.bytes, seconds=cost.seconds, hint="lower rate or shorten path")
        run = simulate_run(plan, true, nominal, rate=rate, noise=noise_of(noise), trials=1, rng=seeds[1])
    return Simulation(nominal, true, injected, path.name if isinstance(path, Plan) else str(path), run)
