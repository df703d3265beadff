"""How the accepted candidates are ranked: a sensor effect's own-residual gain admits it, the whole
held-out cost decides between it and a plant effect (verdict.ranked)."""
from plant.diagnose.fit import Result
from plant.diagnose.verdict import ranked


def _lag(own_gain, held_cost):
    return Result("sensor_lag", "sensor", "signal", True, signal="storage.T_sensor_10", held_cost=held_cost,
                  held_gain=own_gain, accepted=True, local={"gain": own_gain})


def _plant(pid, held_cost, nominal_held):
    return Result(pid, "storage", "simulate", True, held_cost=held_cost,
                  held_gain=1.0 - held_cost / nominal_held, accepted=True)


def test_a_plant_effect_that_removes_more_of_the_cost_leads_a_sensor_effect():
    # rigsim realisation 3's plume_250, as its report gave them: the top sensor's lag removed 38 %
    # of its own residual and 5.8 % of the held-out cost (3.51 -> 3.31), the port plume 26.4 %
    nominal = 3.5104
    lag, plume = _lag(0.378, 3.3057), _plant("storage_mixing", 2.5838, nominal)
    assert [r.id for r in ranked([lag, plume], nominal)] == ["storage_mixing", "sensor_lag"]


def test_a_sensor_effect_that_also_removes_more_of_the_cost_keeps_the_lead():
    nominal = 3.0
    lag, loss = _lag(0.8, 2.4), _plant("heat_loss", 2.7, nominal)   # 20 % of the cost against 10 %
    assert [r.id for r in ranked([loss, lag], nominal)] == ["sensor_lag", "heat_loss"]


def test_plant_effects_alone_rank_by_their_gain():
    nominal = 3.0
    a, b = _plant("heat_loss", 2.0, nominal), _plant("storage_mixing", 1.0, nominal)
    assert [r.id for r in ranked([a, b], nominal)] == ["storage_mixing", "heat_loss"]
