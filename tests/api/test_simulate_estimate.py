"""``omnikin.simulate`` hands its estimate to ``on_cost`` before any work, so a caller (the command
line) can refuse the run with its own limits and names."""

from __future__ import annotations

import importlib

import pytest

import omnikin

WORK = (("omnikin.simulation.kinematic", "simulate_kinematic"), ("omnikin.physics.run", "simulate_physics"))


class Refused(Exception):
    pass


def _no_work(monkeypatch) -> list:
    ran: list = []
    for module, name in WORK:
        monkeypatch.setattr(importlib.import_module(module), name, lambda *a, _n=name, **k: ran.append(_n))
    return ran


def test_a_refusal_in_on_cost_comes_before_the_kinematic_run(monkeypatch):
    ran = _no_work(monkeypatch)
    seen = []

    def refuse(cost):
        seen.append(cost)
        raise Refused

    with pytest.raises(Refused):
        omnikin.simulate("diff-drive", "line 1", rate=50.0, on_cost=refuse)
    assert ran == []
    (cost,) = seen
    # the estimate: samples of the plan at the rate, the simulated time they span, a wall time
    assert cost.duration == pytest.approx(cost.samples / 50.0)
    assert cost.seconds is not None and cost.seconds > 0 and cost.memory > 0


def test_the_physics_engine_is_estimated_before_its_plan_is_sampled_and_again_once_timed(monkeypatch):
    pytest.importorskip("mujoco")
    ran = _no_work(monkeypatch)
    seen = []

    def note(cost):
        seen.append(cost)
        if len(seen) == 2:
            raise Refused

    with pytest.raises(Refused):
        omnikin.simulate("tomasi-omni3", "line 0.2", errors="none", engine="physics", on_cost=note)
    assert ran == []
    first, second = seen
    assert first.seconds is None and first.duration is None  # memory alone, before sampling
    assert second.seconds is not None and second.seconds > 0
    # the run lasts at least its plan: the plan's samples span samples / rate seconds
    assert second.duration >= (second.samples - 1) / 100.0
    assert first.memory >= second.memory  # the first leaves room for the run's tail
