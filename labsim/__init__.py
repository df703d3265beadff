"""labsim: an independent simulator of CoSES house 1, the truth of the diagnosis's public suite.

It shares no code with the twin (no import of plant/components, plant/compiler.py,
plant/connections, plant/controllers, plant/house.py or any kernel of the twin; guarded by
tests/labsim/test_independence.py). Its models are written from the physics reference
(shared/reference/prohmo-physics.md) with choices of its own:

  products.py    the measured tables of the neoTower 2 and the CGB-14 (plant/data, read with
                 plant.tables.read_tables) and clamped linear/bilinear look-up
  generators.py  CHP (start-up, warm-up penalty, steady state, cool-down) and boiler
  storage.py     explicit finite-volume tank: 50 layers, first-order upwind advection in flux form,
                 buoyancy by convective adjustment, conduction, losses, inlet plumes, coil
  network.py     pressure-driven hydraulics: pump curves, branch resistances, check valves,
                 one scalar unknown (the header pressure difference) solved by bracketing
  building.py    mixing station, three-node radiator (exponent law), two-node RC building
  sensors.py     thermowell lag, stagnant-pipe cooling, 0.1 K quantisation, DAQ noise
  control.py     the case study's rule-based controller and a room thermostat, from the reference
  house.py       the assembled plant, explicit 10 s steps, its energy ledger
  recording.py   lab-style recordings (DAQ tags, lab units, columns.toml, meta.json)
  suite.py       the public suite: `python -m labsim.suite --out DIR [--days 7] [--case NAME]`

Water: cp = 4180 J/(kg K), 1 l = 1 kg throughout (one value, so the ledger closes exactly).
"""
