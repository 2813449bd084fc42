"""The display's web side: the pages' files, the event stream, the guard of every request.

No rclpy: :class:`PageServer` serves the person's page and the console over HTTP on the
node's behalf (it calls the display node's ``status``, ``control``, ``tlx_answers`` and
``store_tlx``), :class:`EventHub` fans Server-Sent Events out to every page, and
:class:`RequestGuard` lets only the lab's own pages act (see the display node's docstring for
the rules).
"""

import errno
import http.server
import json
import pathlib
import queue
import secrets
import sys
import threading
import time

from hrc_common.session_control import OPERATOR_SERVICES


WEB = pathlib.Path(__file__).resolve().parent / 'web'
FILES = {'/': ('person.html', 'text/html; charset=utf-8'),
         '/index.html': ('person.html', 'text/html; charset=utf-8'),
         '/console': ('console.html', 'text/html; charset=utf-8'),
         '/scene.js': ('scene.js', 'text/javascript; charset=utf-8')}
# Events kept per client before the oldest are dropped (a stalled browser must not grow memory).
CLIENT_QUEUE = 200
# Largest request body accepted (bytes): a TLX answer is ~150.
MAX_BODY = 10_000
# Connections served at once (pages, consoles, status readers; a lab has a few): one more is
# answered 503 at once and closed, so a flood never takes the process to its descriptor limit.
MAX_CONNECTIONS = 64
# Seconds a connection may stay silent while the server waits for its request (a slow-loris
# client, a browser tab left open without its stream) or stall a write; then it is closed.
IDLE_TIMEOUT_S = 30.0
# Seconds the accept loop rests when the process is out of file descriptors (EMFILE/ENFILE):
# the listening socket stays readable, so retrying at once would spin a core.
ACCEPT_BACKOFF_S = 0.2
BUSY_ANSWER = (b'HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\n'
               b'Content-Length: 37\r\nConnection: close\r\n\r\n'
               b'busy: too many connections; try again')
# Host names every request may name besides the served address (loopback only).
LOOPBACK_NAMES = ('127.0.0.1', 'localhost', '[::1]')
# The header that carries the session's secret, and the placeholder the pages hold for it.
TOKEN_HEADER = 'X-HRC-Token'
TOKEN_PLACEHOLDER = b'__HRC_SESSION_TOKEN__'


def host_name(host_header: str) -> str:
    """Return the host name of a ``Host`` header without the port, lower case."""
    host = host_header.strip().lower()
    if host.startswith('['):                    # [::1]:8765
        return host[:host.find(']') + 1] if ']' in host else host
    return host.rsplit(':', 1)[0] if ':' in host else host


class RequestGuard:
    """Decides whether a request comes from the lab's own page (pure: headers in, reason out).

    ``address`` and ``port`` are where the pages are served; ``token`` the session's secret.
    """

    def __init__(self, address: str, port: int, token: str):
        self.port = port
        self.token = token
        self.hosts = {name.lower() for name in LOOPBACK_NAMES + (address,)}
        self.origins = {f'http://{host}:{port}' for host in self.hosts}

    def refusal(self, method: str, headers) -> str:
        """Return why the request must be refused ('' = it may go on)."""
        host = headers.get('Host')
        if not host:
            return 'no Host header'
        if host_name(host) not in self.hosts:
            return f'foreign Host {host!r}'
        if method == 'GET':
            return ''
        origin = headers.get('Origin')
        if not origin:
            return 'no Origin header on a state-changing request'
        if origin.lower() not in self.origins:
            return f'foreign Origin {origin!r}'
        offered = headers.get(TOKEN_HEADER) or ''
        if not secrets.compare_digest(offered.encode(), self.token.encode()):
            return f'missing or wrong {TOKEN_HEADER} (the session secret of the served page)'
        return ''


def os_error_text(error: OSError) -> str:
    """Return an OSError as its errno name and text, e.g. 'EMFILE: Too many open files'."""
    return f'{errno.errorcode.get(error.errno, error.errno)}: {error.strerror}'


def tlx_body(body: bytes) -> tuple:
    """Return (answer mapping, '') for a TLX request body, or (None, why it is refused).

    Bounded: the body is at most MAX_BODY bytes, and a deeply nested one (which the JSON
    parser meets with RecursionError) is refused like any other malformed body.
    """
    try:
        answer = json.loads(body or b'{}')
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None, 'not JSON'
    if not isinstance(answer, dict):
        return None, 'not a JSON object of the NASA-TLX scales'
    return answer, ''


def event_bytes(name: str, document) -> bytes:
    """Return one Server-Sent Event (strict JSON: no NaN)."""
    return f'event: {name}\ndata: {json.dumps(document, allow_nan=False)}\n\n'.encode()


class EventHub:
    """Fan-out of server-sent events to every connected page; the newest of each kept."""

    KEPT = ('geometry', 'words', 'console', 'tlx')   # sent to a page as soon as it connects

    def __init__(self):
        self._lock = threading.Lock()
        self._clients = []
        self._latest = {}

    def publish(self, name: str, document) -> None:
        """Send an event to every client (a full client queue drops its oldest event)."""
        data = event_bytes(name, document)
        with self._lock:
            if name in self.KEPT:
                self._latest[name] = data
            clients = list(self._clients)
        for client in clients:
            try:
                client.put_nowait(data)
            except queue.Full:
                try:
                    client.get_nowait()
                    client.put_nowait(data)
                except (queue.Empty, queue.Full):
                    pass

    def connect(self) -> queue.Queue:
        """Return a new client queue, primed with the newest kept events."""
        client = queue.Queue(CLIENT_QUEUE)
        with self._lock:
            for name in self.KEPT:
                if name in self._latest:
                    client.put_nowait(self._latest[name])
            self._clients.append(client)
        return client

    def disconnect(self, client) -> None:
        """Forget a client."""
        with self._lock:
            if client in self._clients:
                self._clients.remove(client)

    @property
    def client_count(self) -> int:
        """Return the number of connected pages."""
        with self._lock:
            return len(self._clients)


class PageServer:
    """The HTTP side: files, the event stream, status.json, the controls and the TLX form."""

    def __init__(self, node: 'DisplayNode', port: int,  # noqa: F821 (hrc_live.display_node)
                 max_connections: int = MAX_CONNECTIONS, idle_timeout: float = IDLE_TIMEOUT_S):
        self.node = node
        self.closing = threading.Event()
        self.connections = 0            # connections being served now
        self._count_lock = threading.Lock()
        server = self

        class Handler(http.server.BaseHTTPRequestHandler):
            protocol_version = 'HTTP/1.1'
            timeout = idle_timeout      # socket timeout: http.server closes a silent client

            def do_GET(self):  # noqa: N802 (the name http.server calls)
                server.get(self)

            def do_POST(self):  # noqa: N802
                server.post(self)

            def do_PUT(self):  # noqa: N802 (any other method: 405, after the guard)
                server.other(self)

            # HEAD and TRACE too (http.server would say 501, "not implemented": they are
            # refused on purpose)
            do_DELETE = do_PATCH = do_OPTIONS = do_HEAD = do_TRACE = do_CONNECT = do_PUT  # noqa: N815

            def log_message(self, format, *args):  # noqa: A002
                pass  # one line per request would flood the log

        class Server(http.server.ThreadingHTTPServer):
            def get_request(self):
                try:
                    return super().get_request()
                except OSError as error:
                    if error.errno in (errno.EMFILE, errno.ENFILE):
                        server.node.get_logger().warning(
                            f'out of file descriptors ({os_error_text(error)}): new '
                            f'connections wait', throttle_duration_sec=5.0)
                        time.sleep(ACCEPT_BACKOFF_S)
                    raise

            def process_request(self, request, client_address):
                if not server.admit():
                    try:
                        request.sendall(BUSY_ANSWER)
                    except OSError:
                        pass
                    self.shutdown_request(request)
                    return
                super().process_request(request, client_address)

            def process_request_thread(self, request, client_address):
                try:
                    super().process_request_thread(request, client_address)
                finally:
                    server.release()

            def handle_error(self, request, client_address):
                # One line, never a traceback in the display's log (the request is dropped).
                error = sys.exc_info()[1]
                if isinstance(error, (ConnectionResetError, BrokenPipeError)):
                    return      # the browser went away between two requests: nothing to say
                server.node.get_logger().warning(
                    f'request from {client_address[0]} dropped: {type(error).__name__}: '
                    f'{error}', throttle_duration_sec=5.0)

        self.max_connections = max_connections
        self.httpd = Server(('127.0.0.1', port), Handler)
        self.httpd.daemon_threads = True
        self.address, self.port = self.httpd.server_address[:2]
        self.token = secrets.token_urlsafe(24)
        self.guard = RequestGuard(self.address, self.port, self.token)
        self.thread = threading.Thread(target=self.httpd.serve_forever, name='display-http',
                                       daemon=True)
        self.thread.start()

    def admit(self) -> bool:
        """Count one more connection if there is room; return whether there was."""
        with self._count_lock:
            if self.connections >= self.max_connections:
                return False
            self.connections += 1
            return True

    def release(self) -> None:
        """Count one connection less (its thread ended)."""
        with self._count_lock:
            self.connections -= 1

    @staticmethod
    def answer(request, code: int, body: bytes, content_type: str) -> None:
        """Send a whole answer."""
        request.send_response(code)
        request.send_header('Content-Type', content_type)
        request.send_header('Content-Length', str(len(body)))
        request.send_header('Cache-Control', 'no-store')
        request.end_headers()
        request.wfile.write(body)

    def refused(self, request, method: str) -> bool:
        """Answer 403 and log it when the request is not from the lab's page; say if so."""
        reason = self.guard.refusal(method, request.headers)
        if not reason:
            return False
        path = request.path.split('?', 1)[0]
        self.node.get_logger().warning(
            f'refused {method} {path[:80]} from {request.client_address[0]}: {reason}')
        try:
            self.answer(request, 403, f'refused: {reason}'.encode(), 'text/plain; charset=utf-8')
        except OSError:
            pass
        return True

    def other(self, request) -> None:
        """Answer a method the server does not offer: 405 (after the guard), then close."""
        request.close_connection = True     # a HEAD answer with a body ends the connection
        if not self.refused(request, request.command):
            request.send_response(405)
            request.send_header('Allow', 'GET, POST')
            body = b'GET or POST only'
            request.send_header('Content-Type', 'text/plain; charset=utf-8')
            request.send_header('Content-Length', str(len(body)))
            request.end_headers()
            request.wfile.write(body)

    def get(self, request) -> None:
        """Answer one GET request."""
        path = request.path.split('?', 1)[0]
        if self.refused(request, 'GET'):
            return
        try:
            if path in FILES:
                name, content_type = FILES[path]
                body = (WEB / name).read_bytes().replace(TOKEN_PLACEHOLDER,
                                                         self.token.encode())
                self.answer(request, 200, body, content_type)
            elif path == '/events':
                self.stream(request)
            elif path == '/status.json':
                body = json.dumps(self.node.status(), indent=1, allow_nan=False).encode()
                self.answer(request, 200, body, 'application/json')
            else:
                self.answer(request, 404, b'not here: try /, /console or /status.json',
                            'text/plain; charset=utf-8')
        except (BrokenPipeError, ConnectionResetError):
            pass  # the browser went away mid-answer
        except Exception as error:  # a bug must not kill the server thread; say it plainly
            self.node.get_logger().error(f'GET {path} failed: {type(error).__name__}: {error}',
                                         throttle_duration_sec=5.0)
            try:
                self.answer(request, 503, f'the display could not answer: {error}'.encode(),
                            'text/plain; charset=utf-8')
            except OSError:
                pass

    def stream(self, request) -> None:
        """Push the events to one page until it goes away."""
        request.send_response(200)
        request.send_header('Content-Type', 'text/event-stream')
        request.send_header('Cache-Control', 'no-store')
        request.send_header('Connection', 'keep-alive')
        request.end_headers()
        client = self.node.hub.connect()
        try:
            request.wfile.write(b'retry: 1000\n\n')
            request.wfile.flush()
            while not self.closing.is_set():
                try:
                    data = client.get(timeout=1.0)
                except queue.Empty:
                    data = b': keep-alive\n\n'
                request.wfile.write(data)
                request.wfile.flush()
        finally:
            self.node.hub.disconnect(client)

    def post(self, request) -> None:
        """Answer one POST request: a control button, the TLX form or the gamepad."""
        path = request.path.split('?', 1)[0]
        text_plain = 'text/plain; charset=utf-8'
        try:
            length = int(request.headers.get('Content-Length') or 0)
        except ValueError:
            length = -1
        try:
            if length < 0:
                request.close_connection = True
                self.answer(request, 400, b'bad Content-Length', text_plain)
                return
            if length > MAX_BODY:
                request.close_connection = True
                self.answer(request, 413, f'body over {MAX_BODY} bytes'.encode(), text_plain)
                return
            if self.refused(request, 'POST'):
                request.close_connection = True
                return
            body = request.rfile.read(length) if length else b''
            if path.startswith('/control/') and path[len('/control/'):] in OPERATOR_SERVICES:
                code, text = self.node.control(path[len('/control/'):])
            elif path == '/tlx':
                code, text = self.node.store_tlx(body)
            elif path == '/gamepad':
                code, text = self.node.store_gamepad(body)
            else:
                code, text = 404, ('not here: POST /control/<pause|resume|abort>, /tlx or '
                                   '/gamepad')
            self.answer(request, code, text.encode(), text_plain)
        except (BrokenPipeError, ConnectionResetError):
            pass
        except Exception as error:  # a bug must not kill the server thread; say it plainly
            self.node.get_logger().error(f'POST {path} failed: {type(error).__name__}: {error}',
                                         throttle_duration_sec=5.0)
            try:
                self.answer(request, 503, f'the display could not answer: {error}'.encode(),
                            text_plain)
            except OSError:
                pass

    def close(self) -> None:
        """Stop serving and release the port."""
        self.closing.set()
        self.httpd.shutdown()
        self.httpd.server_close()
