"""How a kind reaches slots it does not own (issue #27, handles): an instance's views allocated once
by whichever kind asks first (`c.views`), another instance's state named without allocating it
(`c.state_of`, checked at assembly)."""
from types import SimpleNamespace

import numpy as np
import pytest

from plant import kinds
from plant.compiler import Context, compile_plant
from plant.component import Instance, Kind as ComponentKind
from plant.components import zone
from plant.errors import ConfigError


class _Probe(ComponentKind):
    """A connection that adds 1 K to the first state of the instance it names (`of`)."""

    name = "test_probe"
    role = "connection"

    def emit(self, c, inst):
        c.emit("signals", f"{c.state_of(inst, c.instances[inst.options['of']])}[0] += 1.0")


def _room():
    return Instance("room", "zone", zone.Params(), {}, "test.toml:1 [room]", 1)


def _plant(monkeypatch, *instances):
    monkeypatch.setitem(kinds.KINDS, _Probe.name, _Probe())
    decl = SimpleNamespace(problems=[], instances={i.name: i for i in instances}, prof=())
    return compile_plant(decl)


def test_views_allocate_once_at_the_first_call():
    room = _room()
    c = Context({"room": room}, kinds.KINDS, [])
    assert c.views(room) == ("x_room", "p_room")
    assert c.views(room, x0=np.array([99.0, 99.0])) == ("x_room", "p_room")  # allocated already
    assert len(c.x0) == len(c.p0) == 1
    assert c.x0[0].tolist() == zone.initial_state(room.params).tolist()
    other = Instance("other", "zone", zone.Params(), {}, "test.toml:2 [other]", 2)
    c.views(other, x0=np.array([5.0, 6.0]))
    assert c.x0[1].tolist() == [5.0, 6.0] and c.x_slices["other"] == (2, 4)


def test_state_of_names_a_state_its_own_kind_allocates_later(monkeypatch):
    """The probe (a connection) emits before the zone: it names the zone's state, the zone
    allocates it when it emits; the layout is the zone's alone."""
    probe = Instance("probe", "test_probe", None, {"of": "room"}, "test.toml:2 [probe]", 2)
    plant = _plant(monkeypatch, _room(), probe)
    assert "x_room[0] += 1.0" in plant.source
    assert list(plant.x_slices) == ["room"] and plant.x_slices["room"] == (0, 2)


def test_a_state_nobody_allocates_is_a_problem_at_assembly(monkeypatch):
    meter = Instance("meter", "measured_consumer", None, {}, "test.toml:1 [meter]", 1)
    probe = Instance("probe", "test_probe", None, {"of": "meter"}, "test.toml:2 [probe]", 2)
    with pytest.raises(ConfigError, match=r"test\.toml:2 \[probe\]: reads the state of 'meter', "
                                          "but no kind allocates one"):
        _plant(monkeypatch, meter, probe)
