"""The viewer's front server: the page with the key script, the key channel, and its guard
against other web sites (real sockets on loopback, a real WebSocket client)."""

import http.client
import json
import queue
import socket

import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from omnikin.errors import InputError
from omnikin.viewer.front import KEYS_PATH, SCRIPT_PATH, FrontServer, parse_key_message
from support.browser import wait_until


def without_source(message: dict) -> dict:
    assert isinstance(message.pop("source"), int)  # every message says which socket it came from
    return message


@pytest.fixture
def front():
    received: queue.SimpleQueue = queue.SimpleQueue()
    server = FrontServer(
        "127.0.0.1", 0, inner="/nonexistent/viser.sock", on_key=lambda m: received.put(without_source(m)), inputs=None
    )
    server.start()
    yield server, received
    server.stop()


def get(server, path, headers=None):
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=5)
    conn.request("GET", path, headers=headers or {})
    response = conn.getresponse()
    return response.status, response.getheader("Content-Type"), response.read()


def test_the_page_is_viser_s_client_with_the_key_script_and_the_script_is_served(front):
    server, _ = front
    status, kind, body = get(server, "/")
    assert status == 200 and kind.startswith("text/html")
    assert f'<script src="{SCRIPT_PATH}"></script></head>'.encode() in body
    assert b"Viser" in body
    status, kind, script = get(server, SCRIPT_PATH)
    assert status == 200 and kind.startswith("application/javascript") and b"/omnikin/keys" in script
    assert get(server, "/../etc/passwd")[0] == 404 and get(server, "/omnikin/")[0] == 404


def test_key_messages_from_the_page_reach_the_robot_and_a_closed_page_releases_every_key(front):
    server, received = front
    origin = f"http://127.0.0.1:{server.port}"
    with connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=origin) as ws:
        ws.send(json.dumps({"type": "press", "action": "forward"}))
        ws.send("not json")
        ws.send(json.dumps({"type": "press", "action": "launch_missiles"}))
        ws.send(json.dumps({"type": "release", "action": "forward"}))
        assert received.get(timeout=5) == {"type": "press", "action": "forward"}
        assert received.get(timeout=5) == {"type": "release", "action": "forward"}
    assert received.get(timeout=5) == {"type": "release_all"}
    assert server.rejected == 2 and server.key_messages == 2


def test_a_long_key_message_closes_its_socket(front):
    server, received = front
    with connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=f"http://127.0.0.1:{server.port}") as ws:
        ws.send(json.dumps({"type": "alive", "pad": "x" * 100_000}))
        with pytest.raises(ConnectionClosed):
            ws.recv(timeout=5)
    assert received.get(timeout=5) == {"type": "release_all"}
    assert server.rejected == 1


@pytest.mark.parametrize("origin", ["http://evil.example", "null", None, "http://127.0.0.1:1"])
def test_a_websocket_from_another_site_or_without_origin_is_refused(front, origin):
    server, received = front
    with pytest.raises(InvalidStatus) as e:
        connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=origin).close()
    assert e.value.response.status_code == 403
    assert received.empty()


@pytest.mark.parametrize(
    "text",
    ['{"type": "press"}', '{"type": "hold", "action": "forward"}', "[1, 2]", '"press"', "{", b"bytes"],
)
def test_messages_that_are_not_key_messages_are_not_taken(text):
    assert parse_key_message(text) is None


def test_a_port_in_use_is_one_line_naming_the_address(front):
    server, _ = front
    other = FrontServer("127.0.0.1", server.port, inner="/nonexistent/viser.sock", on_key=lambda m: None, inputs=None)
    with pytest.raises(
        InputError,
        match=rf"cannot listen on '127\.0\.0\.1':{server.port} \(address already in use\): choose another --port",
    ):
        other.start()


def test_a_flood_of_key_messages_is_dropped_beyond_what_a_page_sends():
    """The key messages' bucket on a clock the test sets: a burst is taken, the rest dropped, and
    the bucket refills at its rate as that clock moves, whatever the pace of this machine."""
    from omnikin.viewer.front import KEY_BURST, KEY_RATE

    now = [0.0]
    server = FrontServer(
        "127.0.0.1", 0, inner="/nonexistent/viser.sock", on_key=lambda m: None, inputs=None, clock=lambda: now[0]
    )
    server.start()
    try:
        with connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=f"http://127.0.0.1:{server.port}") as ws:
            for _ in range(2000):
                ws.send('{"type": "alive"}')
            wait_until(lambda: server.key_messages + server.rejected == 2000, "every key message taken or dropped")
            assert (server.key_messages, server.rejected) == (KEY_BURST, 2000 - KEY_BURST)
            now[0] = 0.1  # refills KEY_RATE * 0.1 s messages
            for _ in range(100):
                ws.send('{"type": "alive"}')
            wait_until(lambda: server.key_messages + server.rejected == 2100, "the next 100 taken or dropped")
        assert server.key_messages == KEY_BURST + round(KEY_RATE * 0.1)
    finally:
        server.stop()


def test_requests_that_are_not_a_get_or_not_http_are_closed_and_counted_without_a_word(front, capfd):
    server, _ = front
    for raw in (b"POST / HTTP/1.1\r\nHost: x\r\n\r\n", b"GARBAGE\r\n\r\n", b"GET / HTTP/1.1\r\nX: " + b"a" * 100_000):
        with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
            s.sendall(raw + b"\r\n\r\n")
            s.settimeout(5)
            try:
                while s.recv(65536):
                    pass
            except OSError:
                pass
    wait_until(lambda: server.problems >= 3, "the three requests counted as problems")
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_websockets_beyond_the_limit_are_closed(front):
    from omnikin.viewer.front import MAX_CONNECTIONS

    server, _ = front
    origin = f"http://127.0.0.1:{server.port}"
    sockets = [connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=origin) for _ in range(MAX_CONNECTIONS)]
    try:
        with connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=origin) as extra:
            with pytest.raises(ConnectionClosed) as e:
                extra.recv(timeout=5)
            assert e.value.rcvd is not None and e.value.rcvd.code == 1013
    finally:
        for ws in sockets:
            ws.close()


@pytest.mark.parametrize("name", ["evil.example", "attacker.com", "127.0.0.1.nip.io"])
def test_a_host_name_that_is_not_this_computer_s_gets_neither_page_nor_socket(front, name):
    """DNS rebinding: a site re-points its name at 127.0.0.1; its page then sends Host and Origin
    with its own name, which match each other but name no address of this computer."""
    server, received = front
    host = f"{name}:{server.port}"
    assert get(server, "/", headers={"Host": host})[0] == 403
    assert upgrade(server, host=host, origin=f"http://{host}").startswith(b"HTTP/1.1 403")
    assert received.empty()


def test_a_request_with_two_host_or_origin_headers_is_refused(front):
    server, _ = front
    own = f"127.0.0.1:{server.port}"
    doubled = f"Host: evil.example:{server.port}\r\n"
    assert upgrade(server, host=own, origin=f"http://{own}", extra=doubled).startswith(b"HTTP/1.1 403")
    assert upgrade(server, host=own, origin=f"http://{own}").startswith(b"HTTP/1.1 101")


def test_localhost_and_address_literals_are_this_computer(front):
    server, received = front
    for host in (f"localhost:{server.port}", f"127.0.0.1:{server.port}"):
        assert get(server, "/", headers={"Host": host})[0] == 200
    with connect(f"ws://localhost:{server.port}{KEYS_PATH}", origin=f"http://localhost:{server.port}") as ws:
        ws.send(json.dumps({"type": "press", "action": "back"}))
        assert received.get(timeout=5) == {"type": "press", "action": "back"}


def test_a_message_beyond_the_limit_closes_its_socket_before_it_is_all_read(front):
    from omnikin.viewer.front import MAX_INCOMING

    server, _ = front
    with connect(f"ws://127.0.0.1:{server.port}{KEYS_PATH}", origin=f"http://127.0.0.1:{server.port}") as ws:
        with pytest.raises(ConnectionClosed) as e:
            ws.send("x" * (MAX_INCOMING + 1))
            ws.recv(timeout=5)
    assert e.value.rcvd is None or e.value.rcvd.code == 1009


def upgrade(server, *, host, origin, extra="", keep=None):
    """A WebSocket upgrade of the key channel sent by hand: the server's first reply bytes. With
    ``keep`` (a list), the open socket is appended to it instead of being closed."""
    raw = socket.create_connection(("127.0.0.1", server.port), timeout=5)
    raw.sendall(
        f"GET {KEYS_PATH} HTTP/1.1\r\nHost: {host}\r\n{extra}Upgrade: websocket\r\nConnection: Upgrade\r\n"
        f"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\nOrigin: {origin}\r\n\r\n".encode()
    )
    reply = raw.recv(4096)
    if keep is None:
        raw.close()
    else:
        keep.append(raw)
    return reply


def test_a_peer_that_never_answers_the_close_does_not_hold_up_the_stop():
    server = FrontServer("127.0.0.1", 0, inner="/nonexistent/viser.sock", on_key=lambda m: None, inputs=None)
    server.start()
    kept: list = []
    own = f"127.0.0.1:{server.port}"
    assert upgrade(server, host=own, origin=f"http://{own}", keep=kept).startswith(b"HTTP/1.1 101")
    raw = kept[0]  # upgraded; from now on it reads nothing and answers nothing
    server.stop()  # waits for its thread START_TIMEOUT (10 s), the close CLOSE_TIMEOUT (1 s)
    raw.close()
    assert not server._thread.is_alive(), "the stop waited for the peer's close beyond CLOSE_TIMEOUT"


def test_this_computer_s_own_names_and_the_served_name_are_trusted():
    from omnikin.viewer.front import own_names, trusted_host

    host = socket.gethostname().lower()
    names = own_names("robot-7.example")
    for name in (host, f"{host.split('.')[0]}.local", "localhost", "robot-7.example", "10.0.0.4", "[fe80::1]"):
        assert trusted_host(f"{name}:8080", names), name
    assert not trusted_host("robot-8.example:8080", names)
    assert not trusted_host(None, names) and not trusted_host("", names)
