"""`twin can-hub`: run the socketcand-speaking TCP hub that lets processes share one CAN bus."""
from __future__ import annotations

import argparse
import asyncio
import json
import sys

from gateway.transports.can_bus import DEFAULT_SOCKETCAND_PORT
from gateway.transports.can_hub import CanHub

EXAMPLES = f"""examples:
  twin can-hub
  twin can-hub --host 127.0.0.1 --port {DEFAULT_SOCKETCAND_PORT}
  # then, in other processes: bus spec socketcand:127.0.0.1:{DEFAULT_SOCKETCAND_PORT}:can0
  #   python-can: can.Bus(interface="socketcand", host="127.0.0.1",
  #                       port={DEFAULT_SOCKETCAND_PORT}, channel="can0", tcp_tune=True)
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "can-hub",
        help="share a CAN bus between processes over TCP (socketcand protocol)",
        description=EXAMPLES + "\nServe a CAN bus on TCP: every frame a client sends reaches "
                    "every other client on the same channel.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1; keep it local)")
    parser.add_argument("--port", type=int, default=DEFAULT_SOCKETCAND_PORT,
                        help=f"TCP port (default {DEFAULT_SOCKETCAND_PORT}; 0 picks a free one)")
    parser.add_argument("--quiet", action="store_true", help="do not print connect/fault events")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    def show(event: dict) -> None:
        if not args.quiet:
            print(json.dumps(event), flush=True)

    hub = CanHub(args.host, args.port, on_event=show)

    async def main() -> None:
        await hub.open()
        print(f"can-hub listening on {hub.host}:{hub.port}; bus spec {hub.spec}", flush=True)
        await hub.serve_forever()

    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        print("can-hub stopped", file=sys.stderr)
    return 0
