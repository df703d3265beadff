"""VirtualSerialPair: two linked pseudo-terminals, a serial cable inside one process.

Why: Modbus RTU needs a serial line, and tests and `twin serve --modbus-rtu virtual` should not
need an adapter or socat. One pseudo-terminal alone does not do: pyserial opens a device path, and
the master side of a pty has none that can be reopened. So two ptys are opened with
`os.openpty()`, both put in raw mode, and a relay thread copies bytes between their two master
ends; the slave ends are ordinary device paths (`/dev/pts/N`), one for the server and one for the
client. A pty has no baud timing: bytes arrive as fast as the relay copies them.

    with VirtualSerialPair() as pair:
        ModbusRtuTransport(devices, pair.server_path, parity="N").start()
        ModbusSerialClient(pair.client_path, parity="N")
"""
from __future__ import annotations

import os
import select
import threading
import tty
from pathlib import Path

from plant.errors import TransportError

#: bytes read from one master per relay wake-up; a Modbus RTU frame is at most 256 bytes.
CHUNK = 4096


class VirtualSerialPair:
    """Two raw pseudo-terminals whose master ends a relay thread bridges in both directions.

    `server_path` and `client_path` are the slave device names. Bytes written to one path are
    read from the other. With `link_dir`, stable symlinks `<link_dir>/server` and
    `<link_dir>/client` point at them (removed again on close).
    """

    def __init__(self, link_dir: str | Path | None = None) -> None:
        self.link_dir = Path(link_dir) if link_dir is not None else None
        self._masters: tuple[int, int] | None = None
        self._slaves: tuple[int, int] | None = None
        self._thread: threading.Thread | None = None
        # the relay thread wakes on the read end of this pipe when close() writes to it
        self._wake: tuple[int, int] | None = None
        self._links: list[Path] = []
        self.server_path = ""
        self.client_path = ""

    # --- life cycle --------------------------------------------------------------------------
    def start(self) -> "VirtualSerialPair":
        if self._thread is not None:
            return self
        master_a, slave_a = os.openpty()
        master_b, slave_b = os.openpty()
        for fd in (master_a, slave_a, master_b, slave_b):
            tty.setraw(fd)  # no echo, no line discipline: bytes pass unchanged (0x0d, 0x03 ...)
        for fd in (master_a, master_b):
            os.set_blocking(fd, False)
        self._masters = (master_a, master_b)
        # the slave fds stay open here so a master never reads EIO while no one has the port open
        self._slaves = (slave_a, slave_b)
        self.server_path, self.client_path = os.ttyname(slave_a), os.ttyname(slave_b)
        self._wake = os.pipe()
        self._thread = threading.Thread(target=self._relay, name="virtual-serial", daemon=True)
        self._thread.start()
        if self.link_dir is not None:
            try:
                self._make_links()
            except BaseException:
                self.close()
                raise
        return self

    def close(self) -> None:
        """Stop the relay thread and close every descriptor; idempotent."""
        if self._thread is None:
            return
        os.write(self._wake[1], b"x")
        self._thread.join(5.0)
        self._thread = None
        for fd in (*self._masters, *self._slaves, *self._wake):
            try:
                os.close(fd)
            except OSError:
                pass
        self._masters = self._slaves = self._wake = None
        for link in self._links:
            link.unlink(missing_ok=True)
        self._links = []

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def __enter__(self) -> "VirtualSerialPair":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # --- internals ---------------------------------------------------------------------------
    def _make_links(self) -> None:
        self.link_dir.mkdir(parents=True, exist_ok=True)
        for name, target in (("server", self.server_path), ("client", self.client_path)):
            link = self.link_dir / name
            if link.exists() and not link.is_symlink():
                raise TransportError(f"{link}: exists and is not a symlink; "
                                     "give a directory where the virtual serial links may be made")
            link.unlink(missing_ok=True)
            link.symlink_to(target)
            self._links.append(link)

    def _relay(self) -> None:
        a, b = self._masters
        wake = self._wake[0]
        peer = {a: b, b: a}
        pending = {a: b"", b: b""}  # bytes waiting to be written to this master
        while True:
            readable = [wake, *(fd for fd in (a, b) if not pending[peer[fd]])]
            writable = [fd for fd in (a, b) if pending[fd]]
            try:
                r, w, _ = select.select(readable, writable, [])
            except (OSError, ValueError):
                return
            if wake in r:
                return
            for fd in r:
                try:
                    data = os.read(fd, CHUNK)
                except BlockingIOError:
                    continue
                except OSError:  # EIO: the slave side is closed and the pair is going away
                    return
                pending[peer[fd]] += data
            for fd in w:
                try:
                    n = os.write(fd, pending[fd])
                except BlockingIOError:
                    continue
                except OSError:
                    return
                pending[fd] = pending[fd][n:]
