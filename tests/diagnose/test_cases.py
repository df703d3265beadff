"""The public suite (small): each single injected effect is named; the nominal twin is not blamed.

Full-size runs with the confusion table: benchmarks/diagnose_cases.py.
"""
import pytest

from plant.diagnose import diagnose, synth
from plant.diagnose.effects import Effect, Param, catalogue, register, REGISTRY

DAYS, TRAIN = 1.2, 0.5
quiet = lambda *a: None  # noqa: E731

CASES = [
    ("none", None, "no_missing_physics", None),
    ("idle_generator_flow", 0.25, "missing_physics", "idle_generator_flow"),
    ("heat_loss", 80.0, "missing_physics", "heat_loss"),
    ("sensor_lag", 600.0, "missing_physics", "sensor_lag"),
    ("storage_mixing", 400.0, "missing_physics", "storage_mixing"),
]


@pytest.mark.parametrize("effect,size,verdict,named", CASES)
def test_case(effect, size, verdict, named):
    rec = synth.make(effect, size, days=DAYS)
    rep = diagnose(rec, train_days=TRAIN, log=quiet)
    assert rep["verdict"] == verdict, rep["finding"]
    assert rep["effect"] == named
    if named == "idle_generator_flow":
        assert abs(rep["parameters"]["idle_flow_chp"]["value"] - size) < 0.2 * size
        assert rep["affected_heldout_rmse_after"] < 0.5 * rep["affected_heldout_rmse_before"]
    if named:
        for s in rep["affected_signals"]:
            assert set(rep["signals"][s]) >= {"rmse_before", "rmse_after", "heldout_rmse_before",
                                              "heldout_rmse_after"}


def test_user_effect_plugs_in():
    @register
    class RadiatorSize(Effect):
        id = "radiator_size_test"
        component = "radiator"
        kind = "simulate"
        params = (Param("Q_nominal", 5000.0, 12000.0, 8778.0, "W"),)

        def overrides(self, theta):
            return {"radiator.Q_nominal": float(theta[0])}

    try:
        rec = synth.make("none", days=1.0)
        effects = [e for e in catalogue() if e.id in ("radiator_size_test", "heat_loss")]
        rep = diagnose(rec, train_days=0.4, effects=effects, log=quiet)
        ids = [c["id"] for c in rep["candidates"]]
        assert "radiator_size_test" in ids
        assert rep["verdict"] == "no_missing_physics"
    finally:
        REGISTRY.pop("radiator_size_test", None)
