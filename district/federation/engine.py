"""The one adapter to the co-simulation engine, HELICS (docs/district.md says why HELICS): a broker,
value federates, vector publications and subscriptions, time requests. No other module imports
helics, so a change of engine touches this file only.

Timing contract of the district: a house granted time t reads the grid's temperatures, steps to
t + step, publishes what it exchanged over [t, t + step] (stamped t) and requests t + step; the
grid runs at t + OFFSET: granted then, it has every house's exchange over [t, t + step], steps its
pipes over the same interval and publishes the temperatures for the next one, which every house
sees when granted t + step. Federates are uninterruptible: a value arriving does not grant an
earlier time than requested.
"""
from __future__ import annotations

import socket
import time

from plant.errors import TwinError

OFFSET = 1e-3  # s: the grid's grants trail the houses' by this much
# Fifty house processes starting on two cores keep a core from answering for tens of seconds:
# HELICS' defaults (30 s to connect, a peer silent for two 5 s ticks is lost) are too tight there.
TIMEOUTS = "--timeout=120s --tick=20s"
# A federate's core binds a port the broker hands it; when another process holds that port (any
# TCP client's source port comes from the same range) the core gives up at once ("Unable to
# connect to broker->unable to register federate": once in ~25 runs of the test suite, where
# other tests open connections meanwhile). A new core asks the broker for another port.
JOIN_ATTEMPTS = 5
JOIN_PAUSE = 1.0  # s between attempts


def _h():
    import helics

    return helics


class Stopped(TwinError):
    """The engine stopped this federate: the district was aborted (a member died) or its broker went away."""


class Broker:
    """A HELICS broker in this process, listening on host:port for `federates` federates."""

    def __init__(self, federates: int, host: str = "127.0.0.1", port: int | None = None, name: str = "district"):
        h = _h()
        self.host, self.port = host, port or free_port(host)
        self._b = h.helicsCreateBroker("zmq", name, f"--federates={federates} --local_interface=tcp://{host} "
                                                    f"--port={self.port} {TIMEOUTS}")

    @property
    def address(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "*") else self.host
        return f"tcp://{host}:{self.port}"

    def connected(self) -> bool:
        return bool(_h().helicsBrokerIsConnected(self._b))

    def abort(self, message: str) -> None:
        """Stop every federate through the engine: their pending time requests raise Stopped."""
        _h().helicsBrokerGlobalError(self._b, 1, message.encode())  # helics 3.6.1's binding wants bytes here

    def close(self, wait_ms: int = 2000) -> None:
        h = _h()
        if not h.helicsBrokerWaitForDisconnect(self._b, wait_ms):
            h.helicsBrokerDisconnect(self._b)
        h.helicsBrokerFree(self._b)


class Federate:
    """A value federate joined to the broker at `broker` (tcp://host:port)."""

    def __init__(self, name: str, broker: str, period: float, offset: float = 0.0, interface: str | None = None):
        """`interface`: this host's address as the broker's host reaches it (the broker connects
        back to each federate's core); None on the broker's own host (loopback)."""
        h = _h()
        info = h.helicsCreateFederateInfo()
        h.helicsFederateInfoSetCoreTypeFromString(info, "zmq")
        host_port = broker.removeprefix("tcp://")
        local = f" --local_interface=tcp://{interface}" if interface else ""
        h.helicsFederateInfoSetCoreInitString(info, f"--federates=1 --broker_address=tcp://{host_port}{local} {TIMEOUTS}")
        h.helicsFederateInfoSetTimeProperty(info, h.HELICS_PROPERTY_TIME_PERIOD, period)
        if offset:
            h.helicsFederateInfoSetTimeProperty(info, h.HELICS_PROPERTY_TIME_OFFSET, offset)
        h.helicsFederateInfoSetFlagOption(info, h.HELICS_FLAG_UNINTERRUPTIBLE, True)
        h.helicsFederateInfoSetFlagOption(info, h.HELICS_FLAG_TERMINATE_ON_ERROR, True)
        self.name = name
        try:
            for attempt in range(1, JOIN_ATTEMPTS + 1):
                try:
                    self._f = h.helicsCreateValueFederate(name, info)
                    break
                except h.HelicsException as exc:
                    if attempt == JOIN_ATTEMPTS or "unable to register federate" not in str(exc):
                        raise
                    time.sleep(JOIN_PAUSE)
        finally:
            h.helicsFederateInfoFree(info)

    def publication(self, key: str, units: str = ""):
        return _h().helicsFederateRegisterGlobalTypePublication(self._f, key, "vector", units)

    def subscription(self, key: str, units: str = ""):
        return _h().helicsFederateRegisterSubscription(self._f, key, units)

    def initialize(self) -> None:
        """Initializing mode: values published now are what the others read at time 0."""
        _h().helicsFederateEnterInitializingMode(self._f)

    def start(self) -> None:
        _h().helicsFederateEnterExecutingMode(self._f)

    def _call(self, fn, *args):
        """An engine call during the run; the engine's refusal after an abort becomes Stopped."""
        h = _h()
        try:
            return fn(*args)
        except h.HelicsException as exc:
            raise Stopped(f"stopped by the engine: {exc}") from None

    def request(self, t: float) -> float:
        return self._call(_h().helicsFederateRequestTime, self._f, t)

    def publish(self, pub, values) -> None:
        self._call(_h().helicsPublicationPublishVector, pub, [float(v) for v in values])

    def read(self, sub) -> list[float]:
        return list(self._call(_h().helicsInputGetVector, sub))

    def close(self) -> None:
        h = _h()
        try:
            h.helicsFederateDisconnect(self._f)
        except h.HelicsException:
            pass  # after an abort the federate is already out of the co-simulation
        h.helicsFederateFree(self._f)


def free_port(host: str = "127.0.0.1") -> int:
    """A port whose successor is free too (the zmq broker binds port and port + 1)."""
    for _ in range(50):
        with socket.socket() as s:
            s.bind((host, 0))
            port = s.getsockname()[1]
        try:
            with socket.socket() as s:
                s.bind((host, port + 1))
            return port
        except OSError:
            continue
    raise OSError(f"no free pair of ports on {host}")


def keys(district: str, house: str) -> tuple[str, str]:
    """(what the house publishes, what the grid publishes to it)."""
    return f"{district}/{house}/exchange", f"{district}/grid/{house}"
