"""The web app's server: ``fruitimpact serve`` (issue 16).

Tornado (HTTP and WebSocket in one small, pure-Python package, the server under Bokeh and Jupyter) serves the
pages, their scripts and styles from this package's ``static`` folder, and a JSON API the pages call.  Nothing
is fetched from elsewhere: the page works on a machine with no internet, and its Content-Security-Policy
forbids any other origin.  The server binds the loopback address unless told otherwise.

Every request is answered, whatever it holds: a refused input with the CLI's one line (``refused``, with the
input it names, for the page to show next to its control), a body too large (413) or not JSON (400) with its
reason, anything unexpected with status 500 and one line; the server goes on.
"""

from __future__ import annotations

import asyncio
import json
import socket
import sys
import traceback
from importlib import resources

import tornado.httpserver
import tornado.netutil
import tornado.web

from fruitimpact.app import explorer
from fruitimpact.impact.outputs import dump_json
from fruitimpact.impact.validation import usage_message

#: Largest JSON request body [bytes] (the explorer's are a few hundred); up to ``MAX_BODY`` one is answered 413,
#: beyond it tornado closes the connection without reading it.
MAX_REQUEST = 64 * 1024
MAX_BODY = 1024 * 1024
#: No script, style, font or image from any other origin.
SECURITY_POLICY = ("default-src 'self'; img-src 'self' data: blob:; style-src 'self'; script-src 'self'; "
                   "connect-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'")
#: Pages by path: (title, file in ``static``).
PAGES = {"/": ("Explorer", "explorer.html")}


def _static() -> str:
    return str(resources.files("fruitimpact.app") / "static")


class _Secure:
    def set_default_headers(self):
        self.set_header("Content-Security-Policy", SECURITY_POLICY)
        self.set_header("X-Content-Type-Options", "nosniff")
        self.set_header("Referrer-Policy", "no-referrer")


class PageHandler(_Secure, tornado.web.RequestHandler):
    def initialize(self, page: str):
        self.page = page

    def get(self):
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.write((resources.files("fruitimpact.app") / "static" / self.page).read_bytes())


class StaticHandler(_Secure, tornado.web.StaticFileHandler):
    pass


class ApiHandler(_Secure, tornado.web.RequestHandler):
    """A JSON call: the body is a JSON object, the answer a JSON object; errors as described in the module."""

    def initialize(self, compute, method: str = "POST"):
        self.compute = compute
        self.SUPPORTED_METHODS = (method,)  # the other answered 405 by tornado (as JSON: write_error)

    def _answer(self, status: int, body: dict) -> None:
        self.set_status(status)
        self.set_header("Content-Type", "application/json; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.finish(dump_json(body, indent=None))

    def write_error(self, status_code: int, **kwargs):  # tornado's own errors (a bad method...), as JSON
        self._answer(status_code, {"error": self._reason})

    async def get(self):  # a route without inputs (the options)
        await self._run()

    async def post(self):
        body = self.request.body
        if len(body) > MAX_REQUEST:
            return self._answer(413, {"error": f"the request is {len(body):,} bytes; at most {MAX_REQUEST:,}"})
        try:
            request = json.loads(body.decode("utf-8")) if body else {}
        except (ValueError, RecursionError) as error:  # not UTF-8, not JSON, nested too deep, a 5000-digit int
            return self._answer(400, {"error": f"the request is not JSON: {str(error)[:200]}"})
        await self._run((request,))

    async def _run(self, arguments=()):
        try:
            result = await asyncio.get_running_loop().run_in_executor(None, self.compute, *arguments)
        except ValueError as error:  # the library's InputError: the CLI's line, and the input it names
            # answered 200, "refused": the request was read and judged (a browser logs every 4xx as a console
            # error; 4xx stays for requests that cannot be read at all)
            argument = getattr(error, "argument", None)
            return self._answer(200, {"refused": True, "error": usage_message(error),
                                      "argument": list(argument) if isinstance(argument, tuple) else argument})
        except Exception as error:  # noqa: BLE001 - the server survives every request
            traceback.print_exc(file=sys.stderr)
            return self._answer(500, {"error": f"internal error: {type(error).__name__}: {error}"})
        self._answer(200, result)


def make_app() -> tornado.web.Application:
    """The tornado application: the pages, ``/static/``, and the JSON API under ``/api/``."""
    routes = [(path, PageHandler, {"page": page}) for path, (_, page) in PAGES.items()]
    routes += [
        (r"/api/options", ApiHandler, {"compute": explorer.options, "method": "GET"}),
        (r"/api/explore", ApiHandler, {"compute": explorer.explore}),
        (r"/api/risk", ApiHandler, {"compute": explorer.risk}),
        (r"/static/(.*)", StaticHandler, {"path": _static()}),
    ]
    return tornado.web.Application(routes, compress_response=True, max_body_size=MAX_BODY)


def is_loopback(host: str) -> bool:
    """Whether ``host`` is a loopback address (only this machine can connect); ``OSError`` if it is no address."""
    infos = socket.getaddrinfo(host, None)
    import ipaddress

    return all(ipaddress.ip_address(info[4][0]).is_loopback for info in infos)


async def _serve(host: str, port: int, ready) -> None:
    server = tornado.httpserver.HTTPServer(make_app(), max_body_size=MAX_BODY)
    sockets = tornado.netutil.bind_sockets(port, address=host)
    server.add_sockets(sockets)
    bound = sockets[0].getsockname()[1]
    ready(host, bound)
    await asyncio.Event().wait()


def serve(host: str = "127.0.0.1", port: int = 8050, ready=None) -> None:
    """Run the web app until interrupted; ``ready(host, port)`` is called once it listens (the port is the one
    bound: ``port=0`` picks a free one)."""
    asyncio.run(_serve(host, port, ready or (lambda h, p: None)))


__all__ = ["MAX_REQUEST", "PAGES", "SECURITY_POLICY", "is_loopback", "make_app", "serve"]
