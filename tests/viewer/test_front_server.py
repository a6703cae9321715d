"""The viewer's front server: the page with the key script, the key channel, and its guard
against other web sites (real sockets on loopback, a real WebSocket client)."""

import http.client
import json
import queue

import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from omnikin.errors import InputError
from omnikin.viewer.front import KEYS_PATH, SCRIPT_PATH, FrontServer, parse_key_message


@pytest.fixture
def front():
    received: queue.SimpleQueue = queue.SimpleQueue()
    server = FrontServer("127.0.0.1", 0, inner_port=9, on_key=received.put)
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
    other = FrontServer("127.0.0.1", server.port, inner_port=9, on_key=lambda m: None)
    with pytest.raises(
        InputError,
        match=rf"cannot listen on '127\.0\.0\.1':{server.port} \(address already in use\): choose another --port",
    ):
        other.start()
