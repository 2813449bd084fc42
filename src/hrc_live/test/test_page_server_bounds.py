"""The page server's bounds, on a real server over loopback (a stand-in for the display node).

Methods it does not offer get 405, a malformed or deeply nested TLX body 400, a silent client
is closed after the idle timeout, one connection over the cap gets 503 at once, and an accept
that fails for want of file descriptors rests instead of spinning.
"""

import errno
import http.client
import socket
import time
from types import SimpleNamespace

from hrc_live import page_server
from hrc_live.page_server import EventHub, PageServer, tlx_body
import pytest

WAIT_S = 60.0   # generous: every wait ends on an event, this is only the failure's limit


class StandInNode:
    """What PageServer asks of the display node; the TLX through the node's own parser."""

    def __init__(self):
        self.hub, self.warnings = EventHub(), []
        self.logger = SimpleNamespace(warning=lambda text, **_: self.warnings.append(text),
                                      error=lambda text, **_: self.warnings.append(text))

    def get_logger(self):
        return self.logger

    def status(self):
        return {'phase': 'training'}

    def store_tlx(self, body):
        answer, problem = tlx_body(body)
        return (400, problem) if problem else (200, 'stored')


@pytest.fixture
def served():
    servers = []

    def serve(**bounds):
        server = PageServer(StandInNode(), 0, **bounds)
        servers.append(server)
        return server
    yield serve
    for server in servers:
        server.close()


def own_headers(server):
    return {'Host': f'127.0.0.1:{server.port}', 'Origin': f'http://127.0.0.1:{server.port}',
            page_server.TOKEN_HEADER: server.token, 'Content-Type': 'application/json'}


def wait_until(condition):
    deadline = time.monotonic() + WAIT_S
    while not condition():
        assert time.monotonic() < deadline, 'the event did not come'
        time.sleep(0.01)


@pytest.mark.parametrize('method', ['HEAD', 'TRACE', 'PUT', 'DELETE', 'OPTIONS'])
def test_methods_it_does_not_offer_get_405(served, method):
    server = served()
    connection = http.client.HTTPConnection('127.0.0.1', server.port, timeout=WAIT_S)
    connection.request(method, '/', headers=own_headers(server))
    reply = connection.getresponse()
    assert (reply.status, reply.getheader('Allow')) == (405, 'GET, POST')


def test_a_malformed_or_deeply_nested_tlx_body_gets_400(served):
    server = served()
    for body in (b'[' * 4_900 + b']' * 4_900, b'{"mental": ', b'\xff\xfe', b'[1, 2]'):
        connection = http.client.HTTPConnection('127.0.0.1', server.port, timeout=WAIT_S)
        connection.request('POST', '/tlx', body=body, headers=own_headers(server))
        reply = connection.getresponse()
        assert reply.status == 400, (body[:20], reply.status, reply.read())
    assert server.node.warnings == []           # a bad body is the client's, not an ERROR


def test_a_silent_client_is_closed_after_the_idle_timeout(served):
    server = served(idle_timeout=0.5)
    silent = socket.create_connection(('127.0.0.1', server.port), timeout=WAIT_S)
    silent.sendall(b'GET / HTTP/1.1\r\n')       # half a request, then nothing (slow loris)
    assert silent.recv(1024) == b''             # the server hung up: end of file
    wait_until(lambda: server.connections == 0)


def test_a_connection_over_the_cap_gets_503_at_once_and_the_rest_are_served(served):
    server = served(max_connections=3)
    idle = [socket.create_connection(('127.0.0.1', server.port), timeout=WAIT_S)
            for _ in range(3)]
    wait_until(lambda: server.connections == 3)
    over = socket.create_connection(('127.0.0.1', server.port), timeout=WAIT_S)
    assert over.recv(1024).startswith(b'HTTP/1.1 503 Service Unavailable')
    for connection in idle:
        connection.close()
    wait_until(lambda: server.connections == 0)
    connection = http.client.HTTPConnection('127.0.0.1', server.port, timeout=WAIT_S)
    connection.request('GET', '/status.json', headers={'Host': f'127.0.0.1:{server.port}'})
    assert connection.getresponse().status == 200


def test_out_of_file_descriptors_the_accept_loop_rests(served, monkeypatch):
    """The listening socket stays readable at EMFILE: a retry at once would spin a core."""
    server = served()
    rests = []
    monkeypatch.setattr(page_server.time, 'sleep', rests.append)

    def out_of_descriptors(sock):
        raise OSError(errno.EMFILE, 'Too many open files')
    # (no connection is pending, so the serving thread does not call accept meanwhile)
    monkeypatch.setattr(socket.socket, 'accept', out_of_descriptors)
    with pytest.raises(OSError):
        server.httpd.get_request()
    assert rests == [page_server.ACCEPT_BACKOFF_S]
    assert any('out of file descriptors (EMFILE' in text for text in server.node.warnings)
