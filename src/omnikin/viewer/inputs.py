"""The one boundary where values from a page enter omnikin: every message a page sends to the
viser server passes :meth:`PageInputs.check` in the front server's relay
(:mod:`omnikin.viewer.front`) before viser, or any control's callback in omnikin, sees it.

viser's client sends each message as one binary WebSocket message, the msgpack of a dict whose
``type`` names a viser message class (viser 1.1, ``viser/_messages.py``). A page may send:

- ``ViewerCameraMessage`` (the mouse moved the view): every number finite, ``fov`` in
  (0, pi) rad, ``0 < near < far``, the image size whole numbers from 1 to
  :data:`MAX_PIXELS`, positions within :data:`MAX_COORDINATE` m;
- ``GuiUpdateMessage``: a new ``value``, and nothing else, of an enabled control of this page
  (``uuid``): a button ``true``; a checkbox a boolean; a slider or number field a finite number
  within its bounds (give or take :data:`BOUND_SLACK` of its range: the page's rounding); a
  dropdown or a button group one of its options; a text field a string of at most
  :data:`MAX_TEXT` characters. Every other property (``min``, ``options``, ``label``,
  ``disabled``, ...) belongs to the server;
- ``TransformControlsUpdateMessage``, ``...DragStartMessage``, ``...DragEndMessage`` of a
  transform control of this page (the goal marker), with a finite pose within
  :data:`MAX_COORDINATE` m;
- ``ScenePointerMessage`` of a click, while the server takes clicks in the scene (the Path
  folder's shift-click), with a ray whose origin is within :data:`MAX_COORDINATE` m and whose
  direction is finite and not zero, one screen position in [0, 1] and a modifier viser names.

Anything else (a type viser would act on but omnikin does not serve, such as a share-URL
request that would open a tunnel to the internet, a file upload, a form; a message that is not
msgpack; extra fields; wrong types; NaN or infinite numbers; huge strings) is refused: it is not
relayed, it is counted (:attr:`PageInputs.refused`, :attr:`PageInputs.last`), and the page that
sent it is told in a one-line notification (:meth:`PageInputs.notice`, a viser notification in
viser's own wire format). The server goes on serving and prints nothing.

A flood of bad messages does not flood the page with notifications: each page has a
:class:`NoticeLimiter` that lets at most one notification go every :data:`NOTICE_INTERVAL`
seconds. The refusals between two notifications are held and counted; the next notification
says how many it covers and gives the last reason ("omnikin refused 250 inputs from this page (N
since the viewer started)"), and the front server sends it as soon as the interval has passed
even if nothing more comes. Every refused message is still counted, one by one.

The controls are looked up, at the time a message arrives, in viser's own tables of the
server's GUI inputs and transform controls (``GuiApi._gui_input_handle_from_uuid``,
``SceneApi._handle_from_transform_controls_name``): a control added later is covered, with its
bounds and options as they are then (the replay's time slider changes its maximum per run).
:class:`PageInputs` checks at start that those tables exist (one line naming the viser version
otherwise).
"""

from __future__ import annotations

import math
import threading
import time
import typing
import uuid

import msgspec
import viser
import zstandard
from viser import _messages

from ..common.messages import shorten
from ..errors import InputError

MAX_TEXT = 256
"""Longest text a page may put in a text field [characters]."""
MAX_PIXELS = 1 << 16
"""Largest image side a page may report [pixels]."""
MAX_COORDINATE = 1e6
"""Largest coordinate a page may send [m] (camera, goal marker)."""
BOUND_SLACK = 1e-9
"""A slider's value may pass its bounds by this fraction of its range: the page rounds to the
step in floating point (50 steps of 0.006 make 0.30000000000000004 on a slider ending at 0.3)."""
NOTICE_SECONDS = 8.0
"""How long a refusal's notification stays on the page [s]."""
NOTICE_INTERVAL = 1.0
"""Least time between two notifications of refusals to one page [s] (:class:`NoticeLimiter`)."""


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _vector(value, size: int, bound: float = MAX_COORDINATE) -> bool:
    return (
        isinstance(value, (list, tuple))
        and len(value) == size
        and all(_is_number(v) and abs(v) <= bound for v in value)
    )


def _not_vector(value, size: int) -> str:
    return f"not {size} finite numbers within {MAX_COORDINATE:g}: {shorten(value)}"


def _fields(message: dict, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> str | None:
    """Why ``message`` does not have exactly the ``required`` fields (and maybe ``optional``)."""
    keys = set(message) - {"type"}
    missing = [k for k in required if k not in keys]
    if missing:
        return f"lacks {', '.join(missing)}"
    extra = sorted(str(k) for k in keys - set(required) - set(optional))
    if extra:
        return f"has fields a page does not send: {shorten(', '.join(extra))}"
    return None


class NoticeLimiter:
    """The notifications of refusals to one page: at most one every ``interval`` [s] of
    ``clock`` (a function returning seconds; the monotonic clock unless a test gives its own),
    every refusal counted (module docstring). Not thread-safe: one page's relay uses it."""

    def __init__(self, interval: float = NOTICE_INTERVAL, clock=time.monotonic):
        self.interval = interval
        self.clock = clock
        self.refused = 0
        """This page's refusals, all of them."""
        self.held = 0
        """Refusals not told yet (a notification went less than ``interval`` ago)."""
        self.last = ""
        """The last refusal's reason."""
        self._next = -math.inf  # clock time from which the next notification may go

    def refuse(self, reason: str) -> int | None:
        """Count a refusal for ``reason``; :meth:`due`."""
        self.refused += 1
        self.held += 1
        self.last = reason
        return self.due()

    def due(self) -> int | None:
        """How many refusals a notification sent now tells (the held ones, this one included), and
        from now on none are held; None when none are held or the last notification went less
        than ``interval`` ago."""
        now = self.clock()
        if self.held == 0 or now < self._next:
            return None
        told, self.held = self.held, 0
        self._next = now + self.interval
        return told

    def wait(self) -> float:
        """Seconds until a held refusal may be told (0 when it may now; ``inf`` when none is held)."""
        if self.held == 0:
            return math.inf
        return max(0.0, self._next - self.clock())


class PageInputs:
    """The boundary of the page's values (module docstring) for the viser server ``server``."""

    def __init__(self, server: viser.ViserServer):
        controls = getattr(server.gui, "_gui_input_handle_from_uuid", None)
        gizmos = getattr(server.scene, "_handle_from_transform_controls_name", None)
        if not isinstance(controls, dict) or not isinstance(gizmos, dict):
            raise InputError(
                f"viser {viser.__version__} is not supported by omnikin view "
                "(its controls cannot be looked up): install viser 1.1"
            )
        self._controls = controls
        self._gizmos = gizmos
        self._pointer = getattr(server.scene, "_scene_pointer_cb", None)  # the scene's click callbacks
        self._lock = threading.Lock()
        self.refused = 0
        """Messages refused since the start."""
        self.last = ""
        """Why the last one was refused (one line)."""
        self._zstd = zstandard.ZstdCompressor(level=1)

    # --- the check ---------------------------------------------------------------------------
    def check(self, data: bytes | str) -> str | None:
        """None when the page's message ``data`` may reach viser; else why not, in one line
        (counted)."""
        try:
            reason = self._reason(data)
        except Exception as e:  # noqa: BLE001 (a check that fails refuses; it never stops the relay)
            reason = f"a message that could not be checked ({type(e).__name__})"
        if reason is not None:
            with self._lock:
                self.refused += 1
                self.last = reason
        return reason

    def _reason(self, data: bytes | str) -> str | None:
        if not isinstance(data, bytes):
            return "a text message (viser's client sends binary ones)"
        try:
            message = msgspec.msgpack.decode(data)
        except (msgspec.DecodeError, ValueError, RecursionError):
            return "a message that is not msgpack"
        if not isinstance(message, dict) or not isinstance(message.get("type"), str):
            return "a message without a type"
        kind = message["type"]
        if kind == "ViewerCameraMessage":
            return self._camera(message)
        if kind == "GuiUpdateMessage":
            return self._gui(message)
        if kind in (
            "TransformControlsUpdateMessage",
            "TransformControlsDragStartMessage",
            "TransformControlsDragEndMessage",
        ):
            return self._gizmo(kind, message)
        if kind == "ScenePointerMessage" and self._pointer:
            return self._click(message)
        return f"a message of type {shorten(kind, 50)}, which this page does not take"

    @staticmethod
    def _click(message: dict) -> str | None:
        wrong = _fields(message, ("event_type", "ray_origin", "ray_direction", "screen_pos", "modifier"))
        if wrong:
            return f"a click message that {wrong}"
        if message["event_type"] != "click":
            return f"a pointer event {shorten(message['event_type'])}, which this page does not take"
        if not _vector(message["ray_origin"], 3):
            return f"a click ray origin that is {_not_vector(message['ray_origin'], 3)}"
        direction = message["ray_direction"]
        if not _vector(direction, 3, math.inf) or not any(direction):
            return f"a click ray direction that is not three finite numbers, not all zero: {shorten(direction)}"
        screen = message["screen_pos"]
        if not (
            isinstance(screen, (list, tuple))
            and len(screen) == 1
            and _vector(screen[0], 2, 1.0)
            and all(0.0 <= v <= 1.0 for v in screen[0])
        ):
            return f"a click screen position that is not one point in [0, 1]: {shorten(screen)}"
        if message["modifier"] is not None and message["modifier"] not in typing.get_args(_messages.KeyModifier):
            return f"a click modifier viser does not name: {shorten(message['modifier'])}"
        return None

    def _camera(self, message: dict) -> str | None:
        fields = ("wxyz", "position", "fov", "near", "far", "image_height", "image_width", "look_at", "up_direction")
        wrong = _fields(message, fields)
        if wrong:
            return f"a camera message that {wrong}"
        for name, size in (("wxyz", 4), ("position", 3), ("look_at", 3), ("up_direction", 3)):
            if not _vector(message[name], size):
                return f"a camera {name} that is {_not_vector(message[name], size)}"
        fov, near, far = message["fov"], message["near"], message["far"]
        if not (_is_number(fov) and 0.0 < fov < math.pi):
            return f"a camera fov that is not in (0, pi) rad: {shorten(fov)}"
        if not (_is_number(near) and _is_number(far) and 0.0 < near < far):
            return f"camera near and far that are not 0 < near < far: {shorten(near)}, {shorten(far)}"
        for name in ("image_height", "image_width"):
            size = message[name]
            if not (isinstance(size, int) and not isinstance(size, bool) and 1 <= size <= MAX_PIXELS):
                return f"a camera {name} that is not a whole number from 1 to {MAX_PIXELS}: {shorten(size)}"
        return None

    def _gui(self, message: dict) -> str | None:
        wrong = _fields(message, ("uuid", "updates"))
        if wrong:
            return f"a control update that {wrong}"
        key, updates = message["uuid"], message["updates"]
        handle = self._controls.get(key) if isinstance(key, str) else None
        if handle is None:
            return f"an update of a control this page does not have: {shorten(key)}"
        label = shorten(getattr(handle, "label", "?"), 40)
        if not isinstance(updates, dict) or list(updates) != ["value"]:
            names = shorten(", ".join(str(k) for k in updates) if isinstance(updates, dict) else updates)
            return f"control {label}: a page may set its value only, not {names}"
        if handle.disabled or not handle.visible:
            return f"control {label} is not enabled"
        value = updates["value"]
        problem = self._value(handle, value)
        return None if problem is None else f"control {label}: {shorten(value)} is not {problem}"

    @staticmethod
    def _value(handle, value) -> str | None:
        """What ``value`` should be for ``handle``, or None when it is that."""
        if isinstance(handle, viser.GuiButtonHandle):
            return None if value is True else "a click (true)"
        if isinstance(handle, viser.GuiCheckboxHandle):
            return None if isinstance(value, bool) else "true or false"
        if isinstance(handle, (viser.GuiSliderHandle, viser.GuiNumberHandle)):
            low, high = handle.min, handle.max
            low = -math.inf if low is None else low
            high = math.inf if high is None else high
            slack = BOUND_SLACK * (high - low) if math.isfinite(high - low) else 0.0
            if _is_number(value) and low - slack <= value <= high + slack:
                return None
            return f"a number from {low:g} to {high:g}"
        if isinstance(handle, (viser.GuiDropdownHandle, viser.GuiButtonGroupHandle)):
            options = tuple(handle.options)
            return None if isinstance(value, str) and value in options else f"one of {shorten(options)}"
        if isinstance(handle, viser.GuiTextHandle):
            return (
                None
                if isinstance(value, str) and len(value) <= MAX_TEXT
                else f"a text of at most {MAX_TEXT} characters"
            )
        return "a value this page takes (omnikin takes none for this kind of control)"

    def _gizmo(self, kind: str, message: dict) -> str | None:
        pose = ("wxyz", "position") if kind == "TransformControlsUpdateMessage" else ()
        wrong = _fields(message, ("name", *pose), ("owner",))
        if wrong:
            return f"a marker message that {wrong}"
        name = message["name"]
        if not isinstance(name, str) or name not in self._gizmos:
            return f"a move of a marker this page does not have: {shorten(name)}"
        if not isinstance(message.get("owner", ""), str):
            return "a marker message whose owner is not a string"
        for field, size in (("wxyz", 4), ("position", 3)):
            if field in pose and not _vector(message[field], size):
                return f"a marker {field} that is {_not_vector(message[field], size)}"
        return None

    # --- the notice ----------------------------------------------------------------------------
    def notice(self, reason: str, told: int = 1) -> bytes:
        """A viser notification (its server-to-client wire format, ``viser.infra._infra.
        _message_producer``: two little-endian sizes, then the zstd-compressed msgpack of the
        messages) saying that ``told`` values were refused since the page's last notification,
        the last one for ``reason``, with the count of all since the start."""
        with self._lock:
            count = self.refused
        what = "an input" if told == 1 else f"{told} inputs"
        show = _messages.NotificationShowMessage(
            uuid=str(uuid.uuid4()),
            props=_messages.NotificationProps(
                title=f"omnikin refused {what} from this page ({count} since the viewer started)",
                body=reason if told == 1 else f"the last: {reason}",
                loading=False,
                with_close_button=True,
                auto_close_seconds=NOTICE_SECONDS,
                color="red",
            ),
        )
        inner = msgspec.msgpack.encode(
            {
                "messages": (show.as_serializable_dict([]),),
                "timestampSec": time.perf_counter(),
                "binaryBufferLengths": (),
            }
        )
        compressed = self._zstd.compress(inner)
        return len(inner).to_bytes(8, "little") + len(compressed).to_bytes(8, "little") + compressed
