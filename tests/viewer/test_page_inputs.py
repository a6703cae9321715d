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

from conftest import run_entry_point
from viewer_wire import ViserClient, start_viewer, stop_viewer

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


def hostile_messages() -> list[dict | bytes | str]:
    """Messages no page of omnikin sends (not of one control)."""
    nan_camera = dict(CAMERA, fov=math.nan)
    return [
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


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    path = tmp_path_factory.mktemp("bag") / "run.bag"
    done = run_entry_point("simulate", "tomasi-omni3", "--path", "line 0.5; spin 90", "--bag", path)
    assert done.returncode == 0, done.stderr
    return path


@pytest.mark.parametrize("mode", ["live", "replay"])
def test_hostile_values_for_every_control_are_refused_counted_and_told_and_the_viewer_goes_on(mode, bag):
    proc, url = start_viewer("tomasi-omni3", *(["--replay", str(bag)] if mode == "replay" else []))
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

        def notices(got):
            return [m for m in got if m.get("type") == "NotificationShowMessage"]

        told = notices(attacker.read(lambda got: len(notices(got)) >= sent, timeout=60))
        assert len(told) == sent
        assert told[-1]["props"]["title"].endswith(f"({sent} since the viewer started)")
        assert all("\n" not in m["props"]["body"] and len(m["props"]["body"]) < 300 for m in told)
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
        assert notices(list(observer.received)) == []  # the notice went to the sender only
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
