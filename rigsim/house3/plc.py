"""The lab PLC's rules for rigsim's house-3 rig (rig description section 4).

The heat-pump valve, heat pump, back-up heater, solar pump and room-thermostat rules are house 2's
with the same sensors and thresholds (reference §12.4: "as SF2"), so house 2's PLC runs on house
3's arrays (rigsim/house3/layout.py extends house 2's layout); its boiler rule writes a state slot
house 3 never reads. House 3 adds the solar three-way valve. The description orders the solar valve
before the solar pump; neither reads the other, so evaluating it last gives the same states.
"""
from __future__ import annotations

from numba import njit

from ..house2.plc import _hyst
from ..house2.plc import plc as _plc2
from .layout import I_SOLV, PR_COLL


@njit(cache=True)
def plc(P, ist, fst, sb, pr, hour, dt):
    """House 3's rules, once a second (sb: the storage's sleeve sensors 1..10 at 0..9)."""
    _plc2(P, ist, fst, sb, pr, hour, dt)
    dT = pr[PR_COLL] - sb[8]   # collector - sensor 9 (1.564 m): UPPER coil > 3 K, LOWER < 2 K
    ist[I_SOLV] = _hyst(ist[I_SOLV], dT > 3.0, dT < 2.0)
