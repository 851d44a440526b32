"""``fruitimpact serve``: the web app (issue 16), an optional extra."""

from __future__ import annotations

import errno
import importlib.util
import sys

from fruitimpact.cli.common import PROG, UsageError, read_option_count

#: The port the app listens on by default.
DEFAULT_PORT = 8050


def add_parsers(sub) -> None:
    serve = sub.add_parser("serve", help="the web app: explore an impact in a browser",
                           description="Start the web app on this machine and print its address. It listens on "
                                       "127.0.0.1 (this machine only) unless --host is given.")
    serve.add_argument("--port", default=str(DEFAULT_PORT), metavar="P",
                       help=f"TCP port, 0 to 65535 (0: a free one; default {DEFAULT_PORT})")
    serve.add_argument("--host", default="127.0.0.1", metavar="H",
                       help="address to listen on (default 127.0.0.1; another address lets anyone on that "
                            "network use the app)")
    serve.set_defaults(func=cmd_serve)


def is_loopback(host: str) -> bool:
    """Whether ``host`` is a loopback address (only this machine can connect); ``OSError`` if it is no address."""
    import ipaddress
    import socket

    return all(ipaddress.ip_address(info[4][0]).is_loopback for info in socket.getaddrinfo(host, None))


def cmd_serve(args) -> int:
    port = read_option_count("--port", args.port, 0, 65535)
    if importlib.util.find_spec("tornado") is None:
        raise UsageError("the web app needs tornado: pip install 'fruitimpact[app]'")
    host = args.host
    try:
        loopback = is_loopback(host)
    except OSError as error:
        raise UsageError(f"argument --host: {host!r} is not an address: {error.strerror or error}") from None
    from fruitimpact.app import server  # tornado and the app only once the arguments are good

    def ready(bound_host, bound_port):
        if not loopback:  # once it listens: an address it cannot take is one line, the refusal
            print(f"{PROG} serve: warning: listening on {host}: anyone on that network can use this app "
                  f"(it has no login)", file=sys.stderr, flush=True)
        shown = f"[{bound_host}]" if ":" in bound_host else bound_host
        print(f"{PROG} serve: http://{shown}:{bound_port}/ (Ctrl-C to stop)", flush=True)

    try:
        server.serve(host, port, ready)
    except OSError as error:  # the port taken, or an address that is not this machine's
        option = "--port" if error.errno == errno.EADDRINUSE else "--host"
        raise UsageError(f"argument {option}: cannot listen on {host}:{port}: {error.strerror or error}") from None
    return 0
