"""The district-heating grid: a supply line and a return line of plug-flow pipes on one tree of nodes,
a central plant at the root, houses drawing and feeding in through their substations.

Physics in words
----------------
Every pipe of the district file is a pair, one in the supply line and one in the return line
(the lab's `SimX_Pipe_<A>to<B>_high/low`, reference §13.4), both `Pipe`s with plug flow and heat
loss (plant/grid/pipe.py). Every node is a small mixed water volume (the manifold and the house
connection pipes; `node_volume`) in each line.

Hydraulics: the houses' substation pumps impose their grid-side flows (the lab's CHN_S_FW_TG_set is
a flow set-point, §13.1); a house extracting takes water from its node of the supply line and
returns it, cooled, to the return line; a house feeding in takes water from the return line and
returns it, heated, to the supply line. On a tree the flow in every pipe follows from these
draws by continuity alone (the sum of the net draws beyond the pipe), in either direction; the
plant at the root is the slack: it sends the district's net draw into the supply line at
T_supply and takes the same mass from the return line (with net feed-in it runs backwards,
taking the surplus from the supply line and returning it at T_return). Pressures do not change
these flows on a tree; the pressure drop of each pipe (Darcy-Weisbach, Swamee-Jain friction) and
the head the plant's pump must give the farthest house are computed from them and recorded.
A meshed grid would need a pressure solve (docs/district.md: why not pandapipes for this one).

Exchange with the houses: over an exchange step a house reports, from its heat meters, the grid
water it took and gave back and the enthalpy of what it gave back; it took its water at the node
temperature the grid published at the step's start. The grid therefore knows every enthalpy that
crossed each substation exactly, and its ledger (plant heat, pipe losses, heat to the houses,
stored heat) closes to round-off.

Numerics: explicit in time within the step, split into sub-steps so that no node receives more
than its own water mass per sub-step (mixed volumes stay bounded by their inflows); each sub-step
applies the pipes' losses, moves the pipes' water, then mixes the nodes (Jacobi: every outflow at
the node temperature of the sub-step's start).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from plant.grid.pipe import Pipe
from plant.water import CP, RHO


@dataclass(frozen=True)
class PipeSpec:
    name: str
    a: str            # the end nearer the plant
    b: str
    length: float = 20.0
    diameter: float = 0.1
    U: float = 0.19
    roughness: float = 1e-4   # m, for the pressure drop only
    wall_capacity: float = 0.0   # J/K, the wall's heat capacity lumped at the ends (Pipe C_wall; 0 = none)
    wall_share_b: float = 0.5    # share of it at end b
    dispersion: float = 0.0      # m2/s, axial dispersion (0 = plug flow)


@dataclass(frozen=True)
class GridSpec:
    plant_node: str
    nodes: tuple[str, ...]
    pipes: tuple[PipeSpec, ...]
    attach: dict = field(default_factory=dict)   # house -> node
    T_supply: float = 70.0
    T_return: float = 40.0
    T_init_supply: float = 30.0
    T_init_return: float = 30.0
    T_env: float = 10.0
    node_volume: float = 0.05  # m3 per node and line


@dataclass
class Draw:
    """What one house exchanged with the grid over one step (all >= 0): grid water taken from the
    supply line and given back to the return line while extracting (with the enthalpy given back),
    and taken from the return line and given back to the supply line while feeding in."""
    M_extracted: float = 0.0
    H_extracted_back: float = 0.0
    M_fed_in: float = 0.0
    H_fed_in_back: float = 0.0


class Grid:
    def __init__(self, spec: GridSpec):
        self.spec = spec
        self.nodes = list(spec.nodes)
        self.index = {n: i for i, n in enumerate(self.nodes)}
        self.houses = list(spec.attach)
        self.house_node = np.array([self.index[spec.attach[h]] for h in self.houses], dtype=np.int64)
        self.pipe_a = np.array([self.index[p.a] for p in spec.pipes], dtype=np.int64)
        self.pipe_b = np.array([self.index[p.b] for p in spec.pipes], dtype=np.int64)
        self.root = self.index[spec.plant_node]
        self.sup = [_pipe(p, spec.T_init_supply) for p in spec.pipes]
        self.ret = [_pipe(p, spec.T_init_return) for p in spec.pipes]
        # which nodes lie beyond each pipe (its b side): continuity gives the pipe's flow
        children: dict[int, list[int]] = {i: [] for i in range(len(self.nodes))}
        for k in range(len(spec.pipes)):
            children[int(self.pipe_a[k])].append(int(self.pipe_b[k]))
        self.beyond = np.zeros((len(spec.pipes), len(self.nodes)))
        for k in range(len(spec.pipes)):
            stack = [int(self.pipe_b[k])]
            while stack:
                n = stack.pop()
                self.beyond[k, n] = 1.0
                stack.extend(children[n])
        self.node_mass = RHO * spec.node_volume
        self.T_sup = np.full(len(self.nodes), float(spec.T_init_supply))
        self.T_ret = np.full(len(self.nodes), float(spec.T_init_return))
        self.t = 0.0
        self.flow = np.zeros(len(spec.pipes))     # kg/s on the supply line, + from a to b
        self.m_plant = 0.0                        # kg/s the plant sends into the supply line
        self.Q_plant = 0.0                        # W over the last step
        self.dp_plant = 0.0                       # Pa the plant's pump gives the farthest house
        self.E = {"plant": 0.0, "to_houses": 0.0}  # J since the start (pipe losses: stored_loss())
        self._E0 = self.stored_energy()

    # --- what the houses see ----------------------------------------------------------------
    def temperatures(self, house: str) -> tuple[float, float]:
        """(supply-line, return-line) temperature at the house's node [degC]."""
        n = self.index[self.spec.attach[house]]
        return float(self.T_sup[n]), float(self.T_ret[n])

    # --- energy -------------------------------------------------------------------------------
    def stored_energy(self) -> float:
        nodes = self.node_mass * CP * (self.T_sup.sum() + self.T_ret.sum())
        return float(nodes + sum(p.energy() for p in self.sup) + sum(p.energy() for p in self.ret))

    def pipe_losses(self) -> float:
        return float(sum(p.E_loss for p in self.sup) + sum(p.E_loss for p in self.ret))

    def ledger(self) -> dict[str, float]:
        """Grid ledger since the start [J]: plant heat in, pipe losses, net heat to the houses
        (extracted minus fed in), stored heat, and the residual (round-off)."""
        dE = self.stored_energy() - self._E0
        loss = self.pipe_losses()
        residual = self.E["plant"] - loss - self.E["to_houses"] - dE
        scale = max(abs(self.E["plant"]), loss, abs(self.E["to_houses"]), 1.0)
        return {"plant": self.E["plant"], "pipe_losses": loss, "to_houses": self.E["to_houses"],
                "delta_stored": dE, "residual": residual, "closure": abs(residual) / scale}

    # --- time ---------------------------------------------------------------------------------
    def step(self, dt: float, draws: dict[str, Draw], published: dict[str, tuple[float, float]]) -> None:
        """Advance by dt with each house's draw over the step, taken at the temperatures
        `published` to it at the step's start (house -> (T_supply, T_return))."""
        nn = len(self.nodes)
        M_ext = np.zeros(nn)
        M_feed = np.zeros(nn)
        H_node_sup = np.zeros(nn)   # enthalpy the houses add (+) / take (-) at each supply node
        H_node_ret = np.zeros(nn)
        for h, d in draws.items():
            n = self.index[self.spec.attach[h]]
            Ts, Tr = published[h]
            M_ext[n] += d.M_extracted
            M_feed[n] += d.M_fed_in
            H_node_sup[n] += d.H_fed_in_back - d.M_extracted * CP * Ts
            H_node_ret[n] += d.H_extracted_back - d.M_fed_in * CP * Tr
        to_houses = -float(H_node_sup.sum() + H_node_ret.sum())  # what the houses took, net
        net = M_ext - M_feed                      # kg drawn from the supply line at each node
        F = self.beyond @ net                     # kg through each supply pipe, + from a to b
        M_plant = float(net.sum())
        inflow = M_ext + M_feed + abs(M_plant) * (np.arange(nn) == self.root)
        for k in range(len(F)):
            inflow[self.pipe_a[k]] += abs(F[k])
            inflow[self.pipe_b[k]] += abs(F[k])
        n_sub = max(1, int(math.ceil(inflow.max() / self.node_mass)))
        h = dt / n_sub
        E_plant = 0.0
        for _ in range(n_sub):
            dH_sup = H_node_sup / n_sub
            dH_ret = H_node_ret / n_sub
            for k, f in enumerate(F / n_sub):
                a, b = int(self.pipe_a[k]), int(self.pipe_b[k])
                self.sup[k].lose(h, self.spec.T_env)
                self.ret[k].lose(h, self.spec.T_env)
                if f == 0.0:
                    continue
                up, down = (a, b) if f > 0 else (b, a)
                m, H = self.sup[k].push(f, self.T_sup[up])
                dH_sup[up] -= m * CP * self.T_sup[up]
                dH_sup[down] += H
                up, down = down, up                   # the return line flows the other way
                m, H = self.ret[k].push(-f, self.T_ret[up])
                dH_ret[up] -= m * CP * self.T_ret[up]
                dH_ret[down] += H
            m = M_plant / n_sub
            if m > 0:      # the plant heats return water to T_supply
                H_in, H_out = m * CP * self.spec.T_supply, m * CP * self.T_ret[self.root]
                dH_sup[self.root] += H_in
                dH_ret[self.root] -= H_out
            elif m < 0:    # net feed-in: the plant takes supply water and returns it at T_return
                H_in, H_out = -m * CP * self.spec.T_return, -m * CP * self.T_sup[self.root]
                dH_ret[self.root] += H_in
                dH_sup[self.root] -= H_out
            else:
                H_in = H_out = 0.0
            E_plant += H_in - H_out
            self.T_sup = self.T_sup + dH_sup / (self.node_mass * CP)
            self.T_ret = self.T_ret + dH_ret / (self.node_mass * CP)
        self.E["plant"] += E_plant
        self.E["to_houses"] += to_houses
        self.flow = F / dt
        self.m_plant = M_plant / dt
        self.Q_plant = E_plant / dt
        self.dp_plant = self._plant_head()
        self.t += dt

    def _plant_head(self) -> float:
        """Pressure the plant's pump gives: supply plus return drop to the farthest house [Pa]."""
        dp = np.array([2.0 * _dp(p, f) for p, f in zip(self.spec.pipes, self.flow)])
        path = self.beyond.T @ dp if len(dp) else np.zeros(len(self.nodes))  # sum of pipes up to each node
        return float(max(path[self.house_node], default=0.0)) if len(self.house_node) else 0.0


def _pipe(p: PipeSpec, T_init: float) -> Pipe:
    """The Pipe of a PipeSpec; the options only when set (the plain pipe otherwise)."""
    if p.wall_capacity or p.dispersion:
        return Pipe(p.length, p.diameter, p.U, T_init, C_wall=p.wall_capacity, wall_share_b=p.wall_share_b,
                    dispersion=p.dispersion)
    return Pipe(p.length, p.diameter, p.U, T_init)


def _dp(p: PipeSpec, m_flow: float) -> float:
    """Darcy-Weisbach pressure drop of one pipe at m_flow [Pa] (Swamee-Jain friction factor)."""
    if m_flow == 0.0:
        return 0.0
    area = math.pi * p.diameter ** 2 / 4.0
    v = abs(m_flow) / (RHO * area)
    re = RHO * v * p.diameter / 4.0e-4          # water near 60 degC: mu = 0.4 mPa s
    if re < 2300.0:
        f = 64.0 / re
    else:
        f = 0.25 / math.log10(p.roughness / (3.7 * p.diameter) + 5.74 / re ** 0.9) ** 2
    return f * p.length / p.diameter * RHO * v * v / 2.0
