"""Links are declared like parameters (`link(default, meaning, type=..., range=...)`) and the
declaration checks them by type in one place (plant/links.py, plant/declaration.py)."""
import pytest

from plant.component import Instance, Link, names_instances
from plant.errors import ConfigError
from plant.house import load_house
from plant.kinds import KINDS
from plant.links import DataSet, Height, SignalName, Valve


def test_every_link_of_every_kind_is_declared_with_a_type():
    for name, kind in KINDS.items():
        for key, spec in kind.LINKS.items():
            assert isinstance(spec, Link), f"{name}.{key}: declare it with link(...)"
            assert spec.type is not None, f"{name}.{key}: give link(...) a type"
            if names_instances(spec) or spec.type in (int, str, DataSet):
                assert spec.range, f"{name}.{key}: a {spec.type} link needs its range"


def test_the_link_types_read_like_the_links_they_declare():
    coil = KINDS["coil"].LINKS
    assert coil["storage"] == Link(coil["storage"].default, "the storage the coil is in", Instance, ("storage",))
    assert coil["top"].type is Height and KINDS["branch"].LINKS["supply"].type is Valve
    assert KINDS["coupling_point"].LINKS["generators"].type == list[Instance]
    assert KINDS["sensor"].LINKS["signal"].type is SignalName
    assert KINDS["boiler"].LINKS["data"].range == ("wolf_cgb14", "wolf_cgb20")


def test_a_list_where_one_instance_is_named_is_reported(tmp_path):
    """Once a crash in the DHW draw's code (a list is no storage name)."""
    with pytest.raises(ConfigError, match=r"\[dhw\] storage = \['dhw_storage'\]: expected instance name\(s\) \(strings\)"):
        load_house("house1", overrides={"dhw.storage": ["dhw_storage"]})


def test_none_is_checked_where_the_link_has_a_default_of_its_own():
    """A Python override can give None (TOML cannot): a data set's None is no data set."""
    with pytest.raises(ConfigError, match=r"\[boiler\] data = None: unknown data set; allowed: wolf_cgb14, wolf_cgb20"):
        load_house("house1", overrides={"boiler.data": None})


def test_one_name_where_a_list_of_instances_is_needed_is_reported_with_the_fix():
    """Once read letter by letter ("its generators: b, e, i, l, o, r")."""
    with pytest.raises(ConfigError) as err:
        load_house("house1", overrides={"switch.generators": "boiler"})
    msg = str(err.value)
    assert '[switch] generators = "boiler": a list of instance names; write generators = ["boiler"]' in msg
    assert "b, e, i" not in msg and "its generators: boiler" in msg
