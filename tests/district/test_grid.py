"""The grid on its own: plug flow against its analytic delay and decay, continuity on a tree, the
ledger, and the district file's errors."""
import math

import numpy as np
import pytest

from district.declaration import load_district
from district.grid import Draw, Grid, GridSpec, PipeSpec
from plant.errors import ConfigError
from plant.grid.pipe import Pipe
from plant.water import CP, RHO


def test_a_front_arrives_after_the_pipes_water_mass_over_the_flow_unsmeared():
    p = Pipe(20.0, 0.1, 0.0, 30.0)          # no loss: transport only
    assert p.mass == pytest.approx(RHO * math.pi * 0.05 ** 2 * 20.0)
    m = 0.5                                  # kg/s: the pipe's 157 kg take 314 s
    out = []
    for _ in range(100):                     # 10 s steps
        M, H = p.push(m * 10.0, 70.0)
        out.append(H / (M * CP))
    delay = p.mass / m
    k = int(delay // 10.0)                   # the step in which the front arrives
    assert all(T == pytest.approx(30.0) for T in out[:k])
    assert all(T == pytest.approx(70.0) for T in out[k + 1:])
    frac = (delay - 10.0 * k) / 10.0         # that step mixes old and new water in proportion
    assert out[k] == pytest.approx(30.0 * frac + 70.0 * (1 - frac), abs=1e-9)


def test_flow_reverses_and_water_comes_back_in_order():
    p = Pipe(20.0, 0.1, 0.0, 30.0)
    p.push(50.0, 80.0)                       # 50 kg of 80 degC in at a
    M, H = p.push(-50.0, 10.0)               # pushed back out of a
    assert H / (M * CP) == pytest.approx(80.0)
    assert p.energy() == pytest.approx(CP * (p.mass - 50.0) * 30.0 + CP * 50.0 * 10.0)


def test_standing_water_cools_exponentially_and_the_loss_is_booked():
    p = Pipe(20.0, 0.1, 0.19, 70.0)
    E0 = p.energy()
    T_env = 10.0
    for _ in range(3600):
        p.lose(1.0, T_env)
    tau = p.mass * CP / (0.19 * 20.0)
    assert p.T[0] == pytest.approx(T_env + 60.0 * math.exp(-3600.0 / tau), rel=1e-12)
    assert E0 - p.energy() == pytest.approx(p.E_loss, rel=1e-12)


def tree():
    return GridSpec("plant", ("plant", "a", "b", "c"),
                    (PipeSpec("pa", "plant", "a"), PipeSpec("ab", "a", "b"), PipeSpec("ac", "a", "c")),
                    attach={"h_b": "b", "h_c": "c", "h_a": "a"}, T_init_supply=65.0, T_init_return=35.0)


def test_pipe_flows_follow_the_draws_by_continuity_in_either_direction_and_the_ledger_closes():
    g = Grid(tree())
    rng = np.random.default_rng(1)
    for k in range(600):
        pub = {h: g.temperatures(h) for h in g.houses}
        draws = {}
        for h in g.houses:
            Ts, Tr = pub[h]
            M = float(rng.uniform(0.0, 0.4)) * 60.0
            if rng.uniform() < 0.5:     # extracting: gives back 25 K colder than it took
                draws[h] = Draw(M_extracted=M, H_extracted_back=M * CP * (Ts - 25.0))
            else:                       # feeding in at 80 degC
                draws[h] = Draw(M_fed_in=M, H_fed_in_back=M * CP * 80.0)
        g.step(60.0, draws, pub)
        net = {h: (d.M_extracted - d.M_fed_in) / 60.0 for h, d in draws.items()}
        assert g.flow[1] == pytest.approx(net["h_b"]) and g.flow[2] == pytest.approx(net["h_c"])
        assert g.flow[0] == pytest.approx(sum(net.values()))
        assert g.m_plant == pytest.approx(sum(net.values()))
    L = g.ledger()
    assert L["pipe_losses"] > 0
    assert L["closure"] < 1e-12
    assert np.all((g.T_sup > 10.0) & (g.T_sup < 81.0)) and np.all((g.T_ret > 10.0) & (g.T_ret < 81.0))


def test_the_plant_head_grows_with_the_square_of_the_flow():
    g = Grid(tree())
    heads = []
    for m in (0.5, 1.0):
        pub = {h: g.temperatures(h) for h in g.houses}
        g.step(60.0, {"h_b": Draw(M_extracted=m * 60.0, H_extracted_back=m * 60.0 * CP * 30.0)}, pub)
        heads.append(g.dp_plant)
    assert heads[1] / heads[0] == pytest.approx(4.0, rel=0.15)   # turbulent: f varies slowly with Re


def test_the_shipped_district_is_the_lab_and_a_bad_file_lists_every_problem(tmp_path):
    d = load_district("coses")
    assert [h.name for h in d.houses] == ["house1", "house2", "house3", "house4", "house5"]
    assert all(p.length == 20.0 and p.diameter == 0.1 and p.U == 0.19 for p in d.grid.pipes)
    bad = tmp_path / "bad.toml"
    bad.write_text('[district]\nstepp = 60\n[plant]\nnode = "plant"\n'
                   '[pipes.a]\nfrom = "plant"\nto = "n1"\n[pipes.b]\nfrom = "n9"\nto = "n1"\n'
                   '[houses.house1]\nnode = "n2"\nsubstation = "maybe"\n[houses.x]\nfile = "house9"\nnode = "n1"\n')
    with pytest.raises(ConfigError) as e:
        load_district(bad)
    text = str(e.value)
    for expected in ("6 problem(s)", f"{bad}:2: [district] stepp: unknown key; did you mean 'step'?",
                     "one pipe into each node", "node 'n9' is not connected to the plant",
                     "[houses.house1] node = 'n2': not a node", "substation = 'maybe': allowed rules, off",
                     "file = 'house9'"):
        assert expected in text, text
