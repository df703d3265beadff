"""The Modbus server's per-connection request handler (a pymodbus ServerRequestHandler subclass).

Two things pymodbus cannot do through `action` are done in a request-handler subclass:
  * per-request context (client address, the real bit count of coil reads) and the per-device
    function-code whitelist, checked before pymodbus touches the datastore;
  * link faults (silent, late, dropped connection, corrupted RTU CRC), the per-device FC43/14
    identification (pymodbus keeps one global identity), and unknown unit ids (TCP: exception
    0x0B, gateway target device failed to respond; RTU: silence, another slave's address);
  * pipelined Modbus TCP requests (several frames in one segment, or a frame's head behind
    another): pymodbus 3.16's handler decodes one frame per received segment, keeps only the
    last request (`last_pdu`) for its deferred `handle_later`, and its `send()` empties the
    receive buffer, so frames behind the first were never answered. Here every frame of a
    segment is decoded and queued, `handle_later` answers the queue in order, and a TCP answer
    leaves the receive buffer alone;
  * limits (connections beyond `max_connections` closed at once, silent ones after `idle_timeout`)
    and malformed frames, counted and consumed one by one before pymodbus sees them (TrafficLog).

The requests a PLC or a PHIL master sends every scan (FC3/FC4 register reads, FC6 single and FC16
multiple writes) are answered here straight from the Device (`_direct`); everything else goes through pymodbus's simulator and
the action callback of gateway/transports/modbus_server.py, which reads the request being served
from REQUEST.
"""
from __future__ import annotations

import asyncio
import contextvars
import logging
import time
from collections import deque
from typing import Any

from pymodbus.constants import ExcCodes
from pymodbus.framer import FramerRTU
from pymodbus.pdu import ExceptionResponse
from pymodbus.pdu.mei_message import ReadDeviceInformationRequest, ReadDeviceInformationResponse
from pymodbus.pdu.register_message import (ReadHoldingRegistersResponse, ReadInputRegistersResponse,
                                           WriteMultipleRegistersResponse, WriteSingleRegisterResponse)
from pymodbus.server.requesthandler import ServerRequestHandler

from gateway.device.device import FC_TABLE, Device
from gateway.transports.modbus_answers import identification
from gateway.transports.traffic_log import mbap_frame

log = logging.getLogger("gateway.transports.modbus_server")
#: (device, pdu, client) of the request being served, for the action callback.
REQUEST: contextvars.ContextVar[tuple[Device, Any, str]] = contextvars.ContextVar("request")


class RequestHandler(ServerRequestHandler):
    """Per-connection handler: client identity, whitelist, FC43, link faults, no-reply cases."""

    def __init__(self, owner: Any, *args: Any) -> None:
        super().__init__(owner, *args)
        self._corrupt = False
        self._tasks: set[asyncio.Task] = set()
        self._peer: str | None = None  # one connection, one client: resolved once
        self._peer_known = False
        self._last_rx = time.monotonic()
        self._idle: asyncio.TimerHandle | None = None
        #: decoded requests waiting for handle_later, in arrival order (one call_soon each)
        self._queue: deque[Any] = deque()

    def _client(self) -> str:
        if self._peer is None or not self._peer_known:
            peer = self.transport.get_extra_info("peername") if self.transport else None
            self._peer_known = isinstance(peer, tuple)
            self._peer = f"{peer[0]}:{peer[1]}" if self._peer_known else str(self.server.gw_port_name)
        return self._peer

    # --- limits and malformed frames (TCP: per connection; RTU: the one serial line) ---------
    def _host(self) -> str:
        client = self._client()
        return client.rsplit(":", 1)[0] if self._peer_known else client

    def callback_connected(self) -> None:
        super().callback_connected()
        gw = self.server
        if gw.gw_kind != "tcp":
            return
        self.max_buffer_size = 1 << 18   # one socket read; pymodbus's 516 bytes drop coalesced frames
        if len(gw.active_connections) > gw.gw_max_connections:
            gw.gw_owner.traffic.connection(self._host(), f"connection refused (limit {gw.gw_max_connections})")
            self.transport.close()
        elif gw.gw_idle_s:
            self._idle = self.loop.call_later(gw.gw_idle_s, self._idle_check)

    def _idle_check(self) -> None:
        self._idle = None
        if not self.transport:
            return
        quiet, limit = time.monotonic() - self._last_rx, self.server.gw_idle_s
        if quiet < limit:
            self._idle = self.loop.call_later(limit - quiet, self._idle_check)
            return
        self.server.gw_owner.traffic.connection(self._host(), f"connection closed (idle {limit:g} s)")
        self.transport.close()

    def connection_lost(self, exc: Exception | None) -> None:
        if self._idle is not None:
            self._idle.cancel()
        if self.recv_buffer and self.transport:   # pymodbus clears the buffer on close
            self._malformed("truncated frame", self.recv_buffer)
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        self._last_rx = time.monotonic()
        if len(self.recv_buffer) + len(data) > self.max_buffer_size:   # pymodbus drops it all
            self._malformed("oversized frame", self.recv_buffer + data)
        super().data_received(data)

    def _malformed(self, kind: str, frame: bytes) -> None:
        self.server.gw_owner.traffic.malformed(self._host(), kind, bytes(frame))

    def callback_data(self, data: bytes, addr: tuple | None = None) -> int:
        """Malformed frames are counted and consumed here one by one (pymodbus's framer cannot
        resynchronise after a bad MBAP header); each well-formed one goes on to pymodbus's
        decoder and into the queue, so every complete frame of a segment is answered (pymodbus
        alone decodes the first and leaves the rest until the next segment arrives)."""
        if self.server.gw_kind != "tcp":
            used = self._decode(data, addr)
            if used and not self.last_pdu:   # pymodbus dropped it: a CRC or a decoding failure
                crc_ok = used > 2 and FramerRTU.check_CRC(data[:used - 2], int.from_bytes(data[used - 2:used], "big"))
                self._malformed("undecodable PDU" if crc_ok else "bad CRC", data[:used])
            return used
        used = 0
        while used < len(data):
            problem, size = mbap_frame(data[used:], self.server.decoder.pdu_table)
            if not size:
                break   # wait for the rest
            frame, used = data[used:used + size], used + size
            if problem is None:
                self._decode(frame, addr)
                if self.last_pdu:
                    continue
                problem = "undecodable PDU"
            self._malformed(problem, frame)
            if problem != "unknown function code":
                continue
            tid = (frame[0] << 8) | frame[1]
            device = self.server.gw_devices.get(frame[6])
            if device is None:
                self._no_target(frame[7], frame[6], tid)
            elif device.link.mode == "none":
                self.server_send(ExceptionResponse(frame[7], ExcCodes.ILLEGAL_FUNCTION, device_id=frame[6],
                                                   transaction=tid), addr)
        return used

    def _decode(self, frame: bytes, addr: tuple | None) -> int:
        """pymodbus decodes one request off `frame` into last_pdu and schedules one handle_later;
        the request is queued for it, so a later frame replacing last_pdu loses nothing."""
        used = super().callback_data(frame, addr)
        if self.last_pdu:
            self._queue.append(self.last_pdu)
        return used

    def _no_target(self, fc: int, unit: int, tid: int) -> None:
        """Modbus TCP: exception 0x0B (gateway target device failed to respond) for a unit id that
        nothing serves, as a Modbus gateway answers (Modbus Application Protocol §7)."""
        self.server_send(ExceptionResponse(fc & 0x7F, ExcCodes.GATEWAY_NO_RESPONSE, device_id=unit,
                                           transaction=tid), None)

    def handle_later(self) -> None:
        """pymodbus passes every request through run_coroutine_threadsafe: a Task, a concurrent
        Future, a self-pipe write and two more event-loop turns, a third of the server's time per
        request. This runs in the loop's own thread already, so a request is answered right here;
        only a late answer or a request for the simulator becomes a task. One call per queued
        request (pymodbus schedules one per decoded frame)."""
        pdu = self._queue.popleft() if self._queue else None
        device = self._admit(pdu) if pdu else None
        if device is None:
            return
        if device.link.mode == "late":
            self._spawn(self._answer_late(device, pdu))
        elif not self._answer(device, pdu):
            self._spawn(self._simulate(device, pdu))

    async def handle_request(self) -> None:
        pdu = self.last_pdu
        device = self._admit(pdu) if pdu else None
        if device is None:
            return
        if device.link.mode == "late":
            await self._answer_late(device, pdu)
        elif not self._answer(device, pdu):
            await self._simulate(device, pdu)

    def _spawn(self, coro: Any) -> None:
        task = self.loop.create_task(coro)
        self._tasks.add(task)  # the loop keeps only a weak reference
        task.add_done_callback(self._tasks.discard)

    def _admit(self, pdu: Any) -> Device | None:
        """The device to answer `pdu`, or None when it is answered already or not at all (refused
        client, unknown unit, a silent or dropped link)."""
        gw = self.server
        device: Device | None = gw.gw_devices.get(pdu.dev_id)
        client = self._client()
        if gw.gw_allow is not None and client.rsplit(":", 1)[0] not in gw.gw_allow:
            if device is not None:
                device.report({"kind": "link", "transport": gw.gw_name, "client": client,
                               "event": "client refused", "reason": "client"})
            if self.transport and gw.gw_name == "modbus-tcp":
                self.transport.close()
            return None
        if device is None:   # TCP: 0x0B; RTU: no reply (someone else's address on the line)
            if gw.gw_kind == "tcp":
                self._no_target(pdu.function_code, pdu.dev_id, pdu.transaction_id)
            return None
        link = device.link
        if link.mode == "silent":
            return None
        if link.mode == "drop":
            if self.transport and gw.gw_name == "modbus-tcp":
                self.transport.abort()
            return None
        return device

    async def _answer_late(self, device: Device, pdu: Any) -> None:
        await asyncio.sleep(device.link.delay_s)
        if not self._answer(device, pdu):
            await self._simulate(device, pdu)

    def _answer(self, device: Device, pdu: Any) -> bool:
        """Answer `pdu` now (whitelist, FC43, FC3/FC4/FC6 from the Device); False if the simulator
        must answer it (the request has been counted)."""
        gw = self.server
        client = self._client()
        refusal = device.check_function(pdu.function_code)
        if refusal is None and isinstance(pdu, ReadDeviceInformationRequest):
            self._send(_identification(device, pdu), pdu)
            return True
        self._corrupt = device.link.mode == "bad_crc" and gw.gw_name == "modbus-rtu"
        try:
            if refusal is not None:
                device.report({"kind": "link", "transport": gw.gw_name, "client": client,
                               "event": f"function {pdu.function_code} refused", "reason": "function"})
                self._send(ExceptionResponse(pdu.function_code, ExcCodes.ILLEGAL_FUNCTION), pdu)
                return True
            # counted by the controller audit (poll rates); the recorder does not log them
            device.report({"kind": "request", "transport": gw.gw_name, "client": client,
                           "fc": pdu.function_code})
            direct = _direct(device, pdu, client, gw.gw_name)
            if direct is None:
                return False
            self._send(direct, pdu)
            return True
        finally:
            self._corrupt = False

    async def _simulate(self, device: Device, pdu: Any) -> None:
        token = REQUEST.set((device, pdu, self._client()))
        self._corrupt = device.link.mode == "bad_crc" and self.server.gw_name == "modbus-rtu"
        try:
            self.last_pdu = pdu  # pymodbus answers self.last_pdu; a later frame may have replaced it
            await super().handle_request()
        finally:
            self._corrupt = False
            REQUEST.reset(token)

    def _send(self, response: Any, pdu: Any) -> None:
        response.transaction_id = pdu.transaction_id
        response.dev_id = pdu.dev_id
        self.server_send(response, self.last_addr)

    def send(self, data: bytes, addr: tuple | None = None) -> None:
        if self._corrupt and data:
            data = data[:-1] + bytes([data[-1] ^ 0xFF])  # last CRC byte flipped
        pending = self.recv_buffer
        super().send(data, addr)
        if self.server.gw_kind == "tcp":
            # pymodbus empties the receive buffer on every send: on TCP that drops the requests a
            # master pipelined behind this one (or the head of its next frame)
            self.recv_buffer = pending


def _direct(device: Device, pdu: Any, client: str, transport: str) -> Any:
    """The answer to a register read (FC3/FC4) or a register write (FC6, FC16), straight from the
    Device: the requests a PLC or a PHIL master (phil/master.py: one FC16 and one FC4 per bench
    and step) sends every scan, so they skip the simulator datastore's per-register checks, the
    task and the action coroutine, which doubled a bench's CPU time per FC16 (the same Device calls
    and refusals as `action`; pymodbus has already checked read counts when decoding). None: not
    one of them."""
    fc = pdu.function_code
    try:
        if fc in (3, 4):
            result = device.read_registers(FC_TABLE[fc], pdu.address, pdu.count)
            if not isinstance(result, list):
                return ExceptionResponse(fc, ExcCodes(result.modbus_code))
            return (ReadHoldingRegistersResponse if fc == 3 else ReadInputRegistersResponse)(
                registers=result, dev_id=pdu.dev_id, transaction_id=pdu.transaction_id)
        if fc == 6:
            value = int(pdu.registers[0])
            if not 0 <= value <= 0xFFFF:
                return ExceptionResponse(fc, ExcCodes.ILLEGAL_VALUE)
            refusal = device.write_registers("holding", pdu.address, [value], client, transport)
            if refusal:
                return ExceptionResponse(fc, ExcCodes(refusal.modbus_code))
            return WriteSingleRegisterResponse(address=pdu.address, registers=[value],
                                               dev_id=pdu.dev_id, transaction_id=pdu.transaction_id)
        if fc == 16:
            # the checks pymodbus's datastore_update makes before it touches the datastore
            words = [int(v) for v in pdu.registers]
            payload = getattr(pdu, "_payload_byte_count", None)
            if not 1 <= pdu.count <= 0x7B or len(words) != pdu.count or (pdu.byte_count is not None and (
                    pdu.byte_count != 2 * pdu.count or (payload is not None and payload != pdu.byte_count))):
                return ExceptionResponse(fc, ExcCodes.ILLEGAL_VALUE)
            refusal = device.write_registers("holding", pdu.address, words, client, transport)
            if refusal:
                return ExceptionResponse(fc, ExcCodes(refusal.modbus_code))
            return WriteMultipleRegistersResponse(address=pdu.address, count=pdu.count,
                                                  dev_id=pdu.dev_id, transaction_id=pdu.transaction_id)
    except Exception:  # server-loop boundary: log, answer 04, keep serving
        log.exception("%s: request failed", device.id)
        return ExceptionResponse(fc, ExcCodes.DEVICE_FAILURE)
    return None


def _identification(device: Device, pdu: Any) -> Any:
    info = identification(device, pdu.read_code, pdu.object_id)
    if info is None:
        return ExceptionResponse(pdu.function_code, ExcCodes.ILLEGAL_ADDRESS)
    return ReadDeviceInformationResponse(read_code=pdu.read_code, information=info, dev_id=pdu.dev_id,
                                         transaction_id=pdu.transaction_id)
