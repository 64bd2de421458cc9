"""Both engines implement the one interface a built dynamic scene uses (:class:`paragym.sim.engine.Sim`), with the
same parameters: a scene runs on either without knowing which."""

from __future__ import annotations

import inspect

import pytest

from paragym.sim.client import PyBulletSim
from paragym.sim.engine import Sim
from paragym.sim.mujoco_sim import MuJoCoSim

MEMBERS = sorted(name for name in vars(Sim) if not name.startswith("_"))


def test_the_interface_names_what_a_scene_uses():
    assert {"drive", "ramp", "servos", "step", "link_frame", "reset_joint", "clearance", "loops"} <= set(MEMBERS)


@pytest.mark.parametrize("engine", [PyBulletSim, MuJoCoSim], ids=lambda e: e.__name__)
@pytest.mark.parametrize("member", MEMBERS)
def test_each_engine_has_the_member_with_its_parameters(engine, member):
    declared = inspect.getattr_static(Sim, member)
    found = inspect.getattr_static(engine, member, None)
    if isinstance(declared, property):  # a property, or an attribute every instance is given
        assert isinstance(found, property) or f"self.{member}: " in inspect.getsource(engine.__init__), \
            f"{engine.__name__} lacks {member}"
        return
    assert found is not None, f"{engine.__name__} lacks {member}"
    if not callable(declared):
        return
    wanted = list(inspect.signature(declared).parameters)
    got = list(inspect.signature(found).parameters)
    assert got == wanted, f"{engine.__name__}.{member}{tuple(got)}: the interface says {tuple(wanted)}"


def test_mujoco_answers_no_name_it_does_not_define():
    """No forwarding of unknown names (``__getattr__``): what MuJoCoSim answers, it declares."""
    assert "__getattr__" not in vars(MuJoCoSim)
