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
import concurrent.futures
import functools
import json
import signal
import sys
import traceback
from importlib import resources

import tornado.httpserver
import tornado.netutil
import tornado.ioloop
import tornado.web
import tornado.websocket

from fruitimpact.app import explorer, line, recording, sphere
from fruitimpact.app.uploads import MAX_UPLOAD, UploadStore
from fruitimpact.impact.outputs import dump_json
from fruitimpact.impact.validation import usage_message

#: Largest JSON request body [bytes] (the explorer's are a few hundred); up to ``MAX_BODY`` one is answered 413,
#: beyond it tornado closes the connection without reading it.
MAX_REQUEST = 64 * 1024
MAX_BODY = 1024 * 1024
#: Workers of the long computations (line audits, sphere logs, recordings), apart from the quick ones.
HEAVY_WORKERS = 2
#: No script, style, font or image from any other origin.
SECURITY_POLICY = ("default-src 'self'; img-src 'self' data: blob:; style-src 'self'; script-src 'self'; "
                   "connect-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'")
#: Pages by path: (title, file in ``static``).
PAGES = {"/": "explorer.html", "/line": "line.html", "/recording": "recording.html", "/monitor": "monitor.html"}


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

    def initialize(self, compute, method: str = "POST", pool=None):
        self.compute = compute
        self.pool = pool  # None: asyncio's default pool (the quick routes)
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
        await _answered(self, self.compute, *arguments, pool=self.pool)


async def _answered(handler, compute, *arguments, pool=None) -> None:
    """Run ``compute(*arguments)`` in a worker thread and answer its result, or its refusal: the library's
    ``InputError`` is answered 200 ``refused``, with the CLI's line and the input it names (the request was read
    and judged: a browser logs every 4xx as a console error, and 4xx stays for requests that cannot be read at
    all); anything else 500 with one line, and the server goes on."""
    try:
        result = await asyncio.get_running_loop().run_in_executor(pool, compute, *arguments)
    except ValueError as error:
        argument = getattr(error, "argument", None)
        return handler._answer(200, {"refused": True, "error": usage_message(error),
                                     "argument": list(argument) if isinstance(argument, tuple) else argument})
    except Exception as error:  # noqa: BLE001 - the server survives every request
        traceback.print_exc(file=sys.stderr)
        return handler._answer(500, {"error": f"internal error: {type(error).__name__}: {error}"})
    handler._answer(200, result)


@tornado.web.stream_request_body
class UploadHandler(_Secure, tornado.web.RequestHandler):
    """A recording uploaded as the request's body (``POST /api/upload?name=FILE``), streamed to the upload store
    as it arrives: never held whole in memory, refused beyond ``MAX_UPLOAD`` bytes."""

    SUPPORTED_METHODS = ("POST",)

    def initialize(self, uploads: UploadStore):
        self.uploads = uploads
        self.writer = None
        self.refused = None

    _answer = ApiHandler._answer
    write_error = ApiHandler.write_error

    def prepare(self):
        length = self.request.headers.get("Content-Length")
        if length is not None and length.isdigit() and int(length) > MAX_UPLOAD:
            self._answer(413, {"error": f"the upload is {int(length):,} bytes; at most {MAX_UPLOAD:,}"})
            return
        self.request.connection.set_max_body_size(MAX_UPLOAD + 1)
        try:
            self.writer = self.uploads.begin(self.get_query_argument("name", ""))
        except ValueError as error:  # an unsupported format: the body is read and dropped, then refused
            self.refused = error

    def data_received(self, chunk: bytes):
        if self.writer is None:
            return
        try:
            self.writer.write(chunk)
        except ValueError as error:
            self.writer.abort()
            self.writer, self.refused = None, error

    def on_connection_close(self):
        if self.writer is not None:  # a cut upload leaves nothing behind
            self.writer.abort()
            self.writer = None

    async def post(self):
        def stored():
            if self.refused is not None:
                raise self.refused
            upload = self.writer.finish()
            self.writer = None
            return {"upload": upload.id, "file": upload.name, "size": upload.size}

        await _answered(self, stored)


class MonitorSocket(tornado.websocket.WebSocketHandler):
    """The live monitor's channel (``/ws/monitor``): the page sends ``{"action": "start", …inputs}`` (the inputs
    of :data:`fruitimpact.app.monitor.MONITOR_INPUTS`) or ``{"action": "stop"}``; the server answers ``started``
    (or ``refused`` with the CLI's line and the input it names), then a ``frame`` every
    ``monitor.FRAME_SECONDS`` while there is news, and ``end`` once the source has ended and every report was
    sent.  One monitor per connection; closing the page stops it."""

    def initialize(self, uploads: UploadStore):
        self.uploads = uploads
        self.monitor = None
        self.ticker = None

    def _send(self, message: dict) -> None:
        try:
            self.write_message(dump_json(message, indent=None))
        except tornado.websocket.WebSocketClosedError:
            self._stop()

    async def on_message(self, message):
        from fruitimpact.app.monitor import FRAME_SECONDS, Monitor

        try:
            request = json.loads(message)
        except (ValueError, RecursionError) as error:
            return self._send({"type": "refused", "error": f"the message is not JSON: {str(error)[:200]}",
                               "argument": None})
        action = request.pop("action", None) if isinstance(request, dict) else None
        if action == "stop":  # the source stops; the detector is flushed and its last reports still sent
            if self.monitor is not None:
                self.monitor.request_stop()
            return None
        if action != "start":
            return self._send({"type": "refused", "error": "action must be start or stop", "argument": "action"})
        await self._stop_now()
        loop = asyncio.get_running_loop()
        try:
            monitor = await loop.run_in_executor(None, Monitor, request, self.uploads)
            started = monitor.start()
        except ValueError as error:
            argument = getattr(error, "argument", None)
            return self._send({"type": "refused", "error": usage_message(error), "argument": argument})
        except Exception as error:  # noqa: BLE001 - the server survives every request
            traceback.print_exc(file=sys.stderr)
            return self._send({"type": "refused", "error": f"internal error: {type(error).__name__}: {error}",
                               "argument": None})
        self.monitor = monitor
        self._send(started)
        self.ticker = tornado.ioloop.PeriodicCallback(self._tick, FRAME_SECONDS * 1000)
        self.ticker.start()

    def _tick(self) -> None:
        monitor = self.monitor
        if monitor is None:
            return
        frame = monitor.frame()
        if frame is not None:
            self._send(frame)
        elif monitor.finished:  # every report sent: the source has ended
            self._send({"type": "end"})
            self._stop()

    def _stop(self) -> None:
        if self.ticker is not None:
            self.ticker.stop()
            self.ticker = None
        monitor, self.monitor = self.monitor, None
        if monitor is not None:
            asyncio.get_running_loop().run_in_executor(None, monitor.stop)

    async def _stop_now(self) -> None:
        if self.ticker is not None:
            self.ticker.stop()
            self.ticker = None
        monitor, self.monitor = self.monitor, None
        if monitor is not None:
            await asyncio.get_running_loop().run_in_executor(None, monitor.stop)

    def on_close(self) -> None:
        self._stop()


def make_app(uploads: UploadStore) -> tornado.web.Application:
    """The tornado application: the pages, ``/static/``, the JSON API under ``/api/`` and the uploads (kept in
    ``uploads``; its owner closes it)."""
    # line audits, sphere logs and recordings take seconds to minutes: their own two workers, so that they queue among
    # themselves and never hold up the explorer's and the impact view's answers (asyncio's default pool)
    heavy = concurrent.futures.ThreadPoolExecutor(HEAVY_WORKERS, thread_name_prefix="fruitimpact-heavy")
    routes = [(path, PageHandler, {"page": page}) for path, page in PAGES.items()]
    routes += [
        (r"/api/upload", UploadHandler, {"uploads": uploads}),
        (r"/api/recording", ApiHandler, {"compute": functools.partial(recording.analyze, uploads=uploads),
                                         "pool": heavy}),
        (r"/api/impact", ApiHandler, {"compute": recording.impact}),
        (r"/ws/monitor", MonitorSocket, {"uploads": uploads}),
        (r"/api/options", ApiHandler, {"compute": explorer.options, "method": "GET"}),
        (r"/api/explore", ApiHandler, {"compute": explorer.explore}),
        (r"/api/risk", ApiHandler, {"compute": explorer.risk}),
        (r"/api/line", ApiHandler, {"compute": line.audit, "pool": heavy}),
        (r"/api/sphere", ApiHandler, {"compute": functools.partial(sphere.audit, uploads=uploads), "pool": heavy}),
        (r"/api/sphere/choices", ApiHandler, {"compute": sphere.choices, "method": "GET"}),
        (r"/static/(.*)", StaticHandler, {"path": _static()}),
    ]
    return tornado.web.Application(routes, compress_response=True, max_body_size=MAX_BODY,
                                   websocket_max_message_size=MAX_REQUEST)


async def _serve(host: str, port: int, ready) -> None:
    uploads = UploadStore()
    try:
        server = tornado.httpserver.HTTPServer(make_app(uploads), max_body_size=MAX_BODY)
        sockets = tornado.netutil.bind_sockets(port, address=host)
        server.add_sockets(sockets)
        bound = sockets[0].getsockname()[1]
        stop = asyncio.Event()
        for signum in (signal.SIGINT, signal.SIGTERM):  # a clean stop: the uploads are removed
            asyncio.get_running_loop().add_signal_handler(signum, stop.set)
        ready(host, bound)
        await stop.wait()
    finally:
        uploads.close()


def serve(host: str = "127.0.0.1", port: int = 8050, ready=None) -> None:
    """Run the web app until SIGINT or SIGTERM; ``ready(host, port)`` is called once it listens (the port is the one
    bound: ``port=0`` picks a free one)."""
    asyncio.run(_serve(host, port, ready or (lambda h, p: None)))


__all__ = ["MAX_REQUEST", "PAGES", "SECURITY_POLICY", "make_app", "serve"]
