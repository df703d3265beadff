"""The boundary of every house: weather, occupancy, household electricity and the hot-water draw
profile, sampled at the step's local time (the `profiles` kind the compiler always adds)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit

from profiles import loaders
from profiles.loaders import sample

from .component import Kind as ComponentKind
from .water import RHO


@njit(cache=True)
def sample_all(t, tau0, prof):
    """Weather and profiles at time t (s since start) -> (T_air, E_dir, E_dif, presence,
    P_el household, DHW draw [kg/s], tau = local time since the profile year start)."""
    w_T, w_dir, w_dif, pres, pel, draw = prof[0]
    st_w, st_pres, st_pel, st_draw = prof[1]
    tau = tau0 + t
    return (sample(w_T, st_w, True, tau), sample(w_dir, st_w, True, tau),
            sample(w_dif, st_w, True, tau), sample(pres, st_pres, True, tau),
            sample(pel, st_pel, False, tau), sample(draw, st_draw, False, tau) * RHO, tau)


@lru_cache(maxsize=8)
def profiles(typeday: int, household_kwh_per_year: float, dhw_litres_per_day: float,
             dhw_series: str = "SF1") -> tuple:
    """The profile arrays the step samples: ((values...), (steps...)). Built once per set of
    arguments and shared (the step only reads them): a diagnosis builds a house per replay."""
    if typeday:
        td = loaders.typeday(typeday, household_kwh_per_year, dhw_litres_per_day)
        w, pres, pel, draw = td, td["presence"], td["P_el"], td["draw"]
    else:
        w = loaders.weather()
        pres = loaders.presence()
        pel = loaders.electricity(household_kwh_per_year)
        draw = loaders.hot_water(dhw_litres_per_day, dhw_series)
    return ((w["T_air"].values, w["E_dir"].values, w["E_dif"].values, pres.values, pel.values,
             draw.values), (w["T_air"].step, pres.step, pel.step, draw.step))


def tau0(start: str, typeday: int) -> float:
    """Local time [s since the profile year start] of t = 0."""
    return loaders.typeday_offset(typeday) if typeday else loaders.start_offset(start)


class Kind(ComponentKind):
    name = "profiles"
    role = "boundary"

    def emit(self, c, inst):
        p = c.param(inst, np.array([inst.options["tau0"]]))
        mod = c.module(__name__)
        c.emit("boundary", f"T_air, E_dir, E_dif, presence, P_hh, m_draw, tau = {mod}.sample_all(t, {p}[0], prof)")
        for name, local in (("weather.T_air", "T_air"), ("weather.E_dir", "E_dir"), ("weather.E_dif", "E_dif"),
                            ("occupancy.presence", "presence"), ("household.P_el", "P_hh")):
            c.values[name] = local
        rows = (("weather.T_air", "degC", "outdoor air temperature", "T_air"),
                ("weather.E_dir", "W/m2", "beam irradiance on the horizontal", "E_dir"),
                ("weather.E_dif", "W/m2", "diffuse irradiance on the horizontal", "E_dif"),
                ("occupancy.presence", "1", "fraction of residents at home", "presence"),
                ("household.P_el", "W", "household electric consumption (ends up as heat in the zone)", "P_hh"))
        for name, unit, desc, local in rows:
            c.emit("signals", f"{c.named_signal(name, unit, 'output', desc, inst.order)} = {local}")
