"""Nothing a page sends stops or pollutes the viewer: a real ``omnikin view`` (live and replay), a
raw client speaking viser's protocol through the front server sends hostile values to every
control of the page and messages the page has no business sending; each one is refused and
counted, the sender gets a one-line notice, no other page sees a control change, the viewer
goes on serving (a valid value after the attack is taken), and its terminal shows no traceback.
"""

from __future__ import annotations

import math
import shutil

import msgspec
import pytest

from support.browser import wait_until
from support.viewer_wire import ViserClient, notices, served, start_viewer, stop_viewer

CAMERA = {
    "type": "ViewerCameraMessage",
    "wxyz": [1.0, 0.0, 0.0, 0.0],
    "position": [3.0, 3.0, 3.0],
    "fov": 1.3,
    "near": 0.01,
    "far": 1000.0,
    "image_height": 768,
    "image_width": 1024,
    "look_at": [0.0, 0.0, 0.0],
    "up_direction": [0.0, 0.0, 1.0],
}
"""A camera message as viser's client sends it when the view moves (captured from a page)."""

NOT_ANY_VALUE = [math.nan, math.inf, -math.inf, None, [1, 2], {"k": 1}, "x" * 200_000, b"\x00" * 16]
"""Values no control takes (every kind of control)."""


def update(key, **updates) -> dict:
    return {"type": "GuiUpdateMessage", "uuid": key, "updates": updates}


def hostile_updates(key: str, control: dict) -> list[dict]:
    """Updates of the control ``key`` (created by ``control``) that it must refuse."""
    props = control["props"]
    kind = control["type"]
    values = list(NOT_ANY_VALUE)
    if kind in ("GuiSliderMessage", "GuiNumberMessage"):
        values += [True, props["max"] + abs(props["max"]) + 1.0, props["min"] - abs(props["min"]) - 1.0, 10**18, "0.1"]
    elif kind in ("GuiDropdownMessage", "GuiButtonGroupMessage"):
        values += ["not an option", 1, True, props["options"][0].upper() + " "]
    elif kind == "GuiButtonMessage":
        values += [False, 1, "click"]
    elif kind == "GuiCheckboxMessage":
        values += [1, "true"]
    hostile = [update(key, value=v) for v in values]
    valid = props.get("options", [None])[0] if "options" in props else props.get("value", True)
    hostile += [
        update(key, label="pwned"),
        update(key, max=1e9, min=-1e9),
        update(key, options=["a", "b"]),
        update(key, value=valid, disabled=True),  # a valid value does not carry a property in
        update(key, visible=False),
        update(key),
        {"type": "GuiUpdateMessage", "uuid": key, "updates": [["value", valid]]},
        {"type": "GuiUpdateMessage", "uuid": key, "updates": {"value": valid}, "excluded_self_client": 0},
    ]
    return hostile


CLICK = {
    "type": "ScenePointerMessage",
    "event_type": "click",
    "ray_origin": [1.0, 2.0, 5.0],
    "ray_direction": [0.1, -0.2, -1.0],
    "screen_pos": [[0.5, 0.5]],
    "modifier": "shift",
}
"""A shift-click on the floor, as viser's client sends it (the live page takes clicks: its Path folder)."""


def hostile_messages() -> list[dict | bytes | str]:
    """Messages no page of omnikin sends (not of one control)."""
    nan_camera = dict(CAMERA, fov=math.nan)
    return [
        dict(CLICK, ray_origin=[math.nan, 0.0, 5.0]),
        dict(CLICK, ray_origin=[1e300, 0.0, 5.0]),
        dict(CLICK, ray_direction=[0.0, 0.0, 0.0]),
        dict(CLICK, ray_direction=[0.0, 0.0, -math.inf]),
        dict(CLICK, event_type="rect-select", screen_pos=[[0.0, 0.0], [1.0, 1.0]]),
        dict(CLICK, screen_pos=[[2.0, 0.5]]),
        dict(CLICK, screen_pos=[]),
        dict(CLICK, modifier="hyper"),
        dict(CLICK, extra=1),
        {k: v for k, v in CLICK.items() if k != "ray_origin"},
        update("no-such-control", value=1.0),
        update(12345, value=1.0),
        {"type": "GuiUpdateMessage", "updates": {"value": 1}},
        {"type": "ShareUrlRequest"},  # viser would open a tunnel to the internet
        {"type": "ShareUrlDisconnect"},
        {
            "type": "FileTransferStartUpload",
            "source_component_uuid": "x",
            "transfer_uuid": "y",
            "filename": "a",
            "mime_type": "b",
            "part_count": 1,
            "size_bytes": 10**12,
        },
        {"type": "RunJavascriptMessage", "source": "alert(1)"},
        {"type": "NoSuchMessage"},
        {"no": "type"},
        [1, 2, 3],
        nan_camera,
        dict(CAMERA, position=[math.inf, 0.0, 0.0]),
        dict(CAMERA, image_width=10**9),
        dict(CAMERA, near=10.0, far=1.0),
        dict(CAMERA, extra="x"),
        {k: v for k, v in CAMERA.items() if k != "fov"},
        {"type": "TransformControlsUpdateMessage", "name": "/goal", "wxyz": [1, 0, 0, 0], "position": [math.nan, 0, 0]},
        {"type": "TransformControlsUpdateMessage", "name": "/goal", "wxyz": [1, 0, 0, 0], "position": [1e300, 0, 0]},
        {"type": "TransformControlsUpdateMessage", "name": "/nothing", "wxyz": [1, 0, 0, 0], "position": [0, 0, 0]},
        {"type": "TransformControlsDragStartMessage", "name": ["/goal"]},
        b"\x91" * 100_000 + b"\xc0",  # a list nested 100000 deep
        b"\xc1 not msgpack",
        b"",
        "a text message",
    ]


@pytest.mark.parametrize("mode", ["live", "replay"])
def test_hostile_values_for_every_control_are_refused_counted_and_told_and_the_viewer_goes_on(mode, line_spin_bag):
    proc, url = start_viewer("tomasi-omni3", *(["--replay", str(line_spin_bag)] if mode == "replay" else []))
    attacker = observer = None
    try:
        observer = ViserClient(url)
        controls = observer.controls()
        kinds = {c["type"] for c in controls.values()}
        expected = {"GuiSliderMessage", "GuiButtonMessage", "GuiButtonGroupMessage"}
        expected |= {"GuiCheckboxMessage"} if mode == "live" else {"GuiDropdownMessage"}
        assert expected <= kinds, kinds  # every kind of control the page has is attacked
        backlog = len(observer.received)  # what the server set itself (a replay's time range) is before
        attacker = ViserClient(url)
        attacker.controls()
        attacker.send(CAMERA)
        sent = 0
        for key, control in controls.items():
            for message in hostile_updates(key, control):
                attacker.send(message)
                sent += 1
        for message in hostile_messages():
            attacker.send(message if isinstance(message, (bytes, str)) else msgspec.msgpack.encode(message))
            sent += 1

        # every refusal is counted and told, a second's refusals in one notice (the page's last
        # ones once the second has passed)
        got = attacker.read(lambda got: sum(n for n, _ in notices(got)) >= sent, timeout=60)
        told = notices(got)
        assert sum(n for n, _ in told) == sent and told[0][0] == 1
        assert told[-1][1] == sent
        bodies = [m["props"]["body"] for m in got if m.get("type") == "NotificationShowMessage"]
        assert all("\n" not in body and len(body) < 300 for body in bodies)
        assert proc.poll() is None

        # the viewer goes on: a valid value from the same socket is taken and reaches the other page
        slider = next(
            k
            for k, c in controls.items()
            if c["type"] == "GuiSliderMessage" and c["props"]["label"].startswith("view size")
        )
        value = controls[slider]["props"]["min"]
        attacker.send(update(slider, value=value))
        observer.read(lambda got: any(m.get("type") == "GuiUpdateMessage" and m.get("uuid") == slider for m in got))
        since = list(observer.received)[backlog:]
        changed = [m for m in since if m.get("type") == "GuiUpdateMessage" and m["uuid"] in controls]
        assert changed == [{"type": "GuiUpdateMessage", "uuid": slider, "updates": {"value": value}}]
        assert notices(list(observer.received)) == []  # the notices went to the sender only
    finally:
        for client in (attacker, observer):
            if client is not None:
                client.close()
        err = stop_viewer(proc)
    assert "Traceback" not in err, err[-3000:]
    assert f"omnikin view: refused {sent} input(s) from pages" in err


def test_a_slider_end_rounded_by_the_page_is_taken_and_a_step_beyond_is_not():
    """The page rounds a slider to its step in floating point: 50 steps of 0.006 are
    0.30000000000000004 on a slider ending at 0.3 (a user dragging to the end); one more step is
    past the end."""
    from omnikin.viewer.inputs import PageInputs
    from omnikin.viewer.serving import quiet, start_viser

    server, folder = start_viser()
    try:
        slider = server.gui.add_slider("v", -0.3, 0.3, 0.006, 0.0)
        inputs = PageInputs(server)
        key = slider._impl.uuid
        end = sum([0.006] * 50)
        assert end > 0.3  # the rounding happens
        assert inputs.check(msgspec.msgpack.encode(update(key, value=end))) is None
        assert inputs.check(msgspec.msgpack.encode(update(key, value=-end))) is None
        beyond = inputs.check(msgspec.msgpack.encode(update(key, value=0.306)))
        assert beyond == "control 'v': 0.306 is not a number from -0.3 to 0.3"
        assert inputs.refused == 1
    finally:
        with quiet():
            server.stop()
        shutil.rmtree(folder, ignore_errors=True)


class ManualClock:
    """A clock the test sets [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_a_flood_of_refusals_is_counted_one_by_one_and_told_at_most_once_an_interval():
    from omnikin.viewer.inputs import NOTICE_INTERVAL, NoticeLimiter

    clock = ManualClock()
    limiter = NoticeLimiter(clock=clock)
    told: list[tuple[float, int]] = []  # (time, refusals told)
    # 10 000 refusals over 5 s of the clock, then nothing: one notice at the first, one per interval
    for k in range(10_000):
        clock.now = k * 5.0 / 10_000
        n = limiter.refuse(f"refusal {k}")
        if n is not None:
            told.append((clock.now, n))
    assert limiter.refused == 10_000
    times = [t for t, _ in told]
    assert told[0] == (0.0, 1)
    assert all(b - a >= NOTICE_INTERVAL for a, b in zip(times, times[1:], strict=False))
    assert len(told) == 5  # at 0, 1, 2, 3, 4 s: the clock stopped just short of 5 s
    assert limiter.due() is None and limiter.wait() == pytest.approx(times[-1] + NOTICE_INTERVAL - clock.now)
    clock.now = times[-1] + NOTICE_INTERVAL
    held = limiter.held
    assert limiter.wait() == 0.0 and limiter.due() == held and limiter.held == 0
    assert sum(n for _, n in told) + held == 10_000  # every refusal told, once
    assert limiter.last == "refusal 9999" and limiter.wait() == math.inf
    # after a quiet interval the next refusal is told at once
    clock.now += NOTICE_INTERVAL
    assert limiter.refuse("one more") == 1


def test_a_page_flooding_bad_messages_gets_a_notice_an_interval_with_every_refusal_counted():
    """A real front server and viser behind it, the notices' interval on a clock the test sets:
    the flood is told in one notice at its first message and one for the rest once the clock
    has passed the interval, whatever the pace of this machine."""
    from omnikin.viewer.front import FrontServer
    from omnikin.viewer.inputs import NOTICE_INTERVAL, PageInputs
    from omnikin.viewer.serving import quiet, start_viser

    clock = ManualClock()
    server, folder = start_viser()
    inputs = PageInputs(server)
    front = FrontServer("127.0.0.1", 0, str(folder / "viser.sock"), on_key=lambda m: None, inputs=inputs, clock=clock)
    front.start()
    client = None
    try:
        client = ViserClient(front.url)
        flood = 500
        for k in range(flood):
            client.send(update("no such control", value=k))
        client.read(lambda got: len(notices(got)) >= 1)
        wait_until(lambda: inputs.refused == flood, "every message of the flood checked")
        assert notices(client.received) == [(1, 1)]  # the rest held: the clock has not moved
        clock.now = NOTICE_INTERVAL
        client.read(lambda got: len(notices(got)) >= 2)
        assert notices(client.received) == [(1, 1), (flood - 1, flood)]
        # a second flood within the next interval is held whole, then told in one notice
        for _ in range(flood):
            client.send(b"not msgpack")
        wait_until(lambda: inputs.refused == 2 * flood, "every message of the second flood checked")
        assert len(notices(client.received)) == 2
        clock.now = 2 * NOTICE_INTERVAL
        client.read(lambda got: len(notices(got)) >= 3)
        assert notices(client.received) == [(1, 1), (flood - 1, flood), (flood, 2 * flood)]
        last = [m for m in client.received if m.get("type") == "NotificationShowMessage"][-1]
        assert last["props"]["body"] == "the last: a message that is not msgpack"
    finally:
        if client is not None:
            client.close()
        front.stop()
        with quiet():
            server.stop()
        shutil.rmtree(folder, ignore_errors=True)


def test_a_shift_click_on_the_floor_adds_the_waypoint_where_its_ray_meets_the_floor():
    from omnikin import load_robot
    from omnikin.viewer.app import LiveViewer
    from omnikin.viewer.live import LiveRobot

    with served(LiveViewer(LiveRobot(load_robot("tomasi-omni3")), "127.0.0.1", 0)) as viewer:
        client = ViserClient(viewer.url)
        try:
            client.controls()
            client.send(msgspec.msgpack.encode(CAMERA))  # (viser knows a page by its camera: clicks come after)
            wait_until(lambda: viewer.server.get_clients(), "the page known to viser")
            client.send(msgspec.msgpack.encode(CLICK))
            wait_until(lambda: viewer.path.waypoints, "a waypoint from the click")
        finally:
            client.close()
        # the ray (1, 2, 5) + k (0.1, -0.2, -1) meets z = 0 at k = 5: (1.5, 1.0)
        assert viewer.path.waypoints == [pytest.approx((1.5, 1.0), abs=1e-12)]
        assert viewer.servers.inputs.refused == 0
