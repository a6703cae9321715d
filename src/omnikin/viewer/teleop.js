// omnikin view: keyboard teleop for the viser page (served by omnikin.viewer.front).
//
// viser's client sends no key events to Python, so this script, injected into its page, watches
// the keys itself and sends each press and release of a teleop key over its own WebSocket
// (/omnikin/keys on the page's origin) as JSON: {"type": "press"|"release", "action": NAME},
// {"type": "release_all"} when the page loses the focus, and {"type": "alive"} every 100 ms
// while a key is held (the server releases every key when a held key falls silent: a closed
// tab or a lost link stops the robot). Keys typed into a text field, and keys with Ctrl, Alt or
// Meta, are left to the page.
//
// When the server is gone (the key socket closed and a new one cannot be opened), a banner across
// the top of the page says so plainly (#omnikin-gone); it goes when the server answers again.
(() => {
  "use strict";
  const ACTIONS = {
    w: "forward", s: "back", a: "left", d: "right", q: "turn_left", e: "turn_right",
    " ": "stop", "[": "steer_right", "]": "steer_left",
    "1": "camera_free", "2": "camera_top", "3": "camera_follow", "4": "camera_run",
  };
  const held = new Set();
  let socket = null;
  let sent = 0;

  let connected = false;  // the server answered at least once

  function gone(shown) {
    let banner = document.getElementById("omnikin-gone");
    if (!shown) {
      if (banner !== null) banner.remove();
      return;
    }
    if (banner !== null || document.body === null) return;
    banner = document.createElement("div");
    banner.id = "omnikin-gone";
    banner.setAttribute("role", "alert");
    banner.textContent = "The omnikin viewer has stopped (or this computer lost the link to it): "
      + "this page no longer shows or drives the robot. Start omnikin view again and reload the page.";
    banner.style.cssText = "position:fixed;top:0;left:0;right:0;z-index:100000;padding:12px 16px;"
      + "background:#b00020;color:#fff;font:bold 16px sans-serif;text-align:center";
    document.body.appendChild(banner);
  }

  function connect() {
    const url = new URL("/omnikin/keys", window.location.href);
    url.protocol = url.protocol === "https:" ? "wss:" : "ws:";
    let opened = false;
    socket = new WebSocket(url.href);
    socket.onopen = () => {
      opened = connected = true;
      document.documentElement.dataset.omnikinKeys = "connected";
      gone(false);
    };
    socket.onclose = () => {
      document.documentElement.dataset.omnikinKeys = "closed";
      socket = null;
      if (connected && !opened) gone(true);  // closed, and no new socket: the server is gone
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
