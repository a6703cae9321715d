// omnikin view: keyboard teleop for the viser page (served by omnikin.viewer.front).
//
// viser's client sends no key events to Python, so this script, injected into its page, watches
// the keys itself and sends each press and release of a teleop key over its own WebSocket
// (/omnikin/keys on the page's origin) as JSON: {"type": "press"|"release", "action": NAME},
// {"type": "release_all"} when the page loses the focus, and {"type": "alive"} every 100 ms
// while a key is held (the server releases every key when a held key falls silent: a closed
// tab or a lost link stops the robot). Keys typed into a text field, and keys with Ctrl, Alt or
// Meta, are left to the page.
(() => {
  "use strict";
  const ACTIONS = {
    w: "forward", s: "back", a: "left", d: "right", q: "turn_left", e: "turn_right",
    " ": "stop", "[": "steer_right", "]": "steer_left",
    "1": "camera_free", "2": "camera_top", "3": "camera_follow",
  };
  const held = new Set();
  let socket = null;
  let sent = 0;

  function connect() {
    const url = new URL("/omnikin/keys", window.location.href);
    url.protocol = url.protocol === "https:" ? "wss:" : "ws:";
    socket = new WebSocket(url.href);
    socket.onopen = () => { document.documentElement.dataset.omnikinKeys = "connected"; };
    socket.onclose = () => {
      document.documentElement.dataset.omnikinKeys = "closed";
      socket = null;
      window.setTimeout(connect, 500);
    };
  }

  function send(message) {
    if (socket !== null && socket.readyState === WebSocket.OPEN) {
      socket.send(JSON.stringify(message));
      sent += 1;
      document.documentElement.dataset.omnikinKeysSent = String(sent);
    }
  }

  function typing(event) {
    const target = event.target;
    return target instanceof HTMLElement
      && (target.isContentEditable || ["INPUT", "TEXTAREA", "SELECT"].includes(target.tagName));
  }

  function keyAction(event) {
    return ACTIONS[event.key.length === 1 ? event.key.toLowerCase() : event.key];
  }

  window.addEventListener("keydown", (event) => {
    if (event.ctrlKey || event.altKey || event.metaKey || typing(event)) return;
    const action = keyAction(event);
    if (action === undefined) return;
    event.preventDefault();
    event.stopPropagation();
    if (event.repeat || held.has(action)) return;
    held.add(action);
    send({ type: "press", action });
  }, true);

  window.addEventListener("keyup", (event) => {
    const action = keyAction(event);  // a held key is released whatever else is pressed now
    if (action === undefined || !held.delete(action)) return;
    event.preventDefault();
    event.stopPropagation();
    send({ type: "release", action });
  }, true);

  window.addEventListener("blur", () => {
    held.clear();
    send({ type: "release_all" });
  });

  window.setInterval(() => { if (held.size > 0) send({ type: "alive" }); }, 100);
  connect();
})();
