// gi view: the page. Shows the frames the server sends over the WebSocket, sends camera,
// light and object changes and panel settings back (the messages of gi/viewer/messages.py),
// and acknowledges each frame once drawn, so that the server never sends faster than the
// page draws. No network access besides this server; no libraries.
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const view = $("view");
  const canvas = $("frame");
  const ctx = canvas.getContext("2d");
  const marks = $("marks");
  const chart = $("chart");

  // What the server said last (hello/state messages), and this page's own camera, which
  // it changes at once while the user drags and sends at most once per animation frame.
  let server = null;
  let camera = null;
  let clientId = null;
  let socket = null;
  let seq = 0;
  let pendingCamera = false;
  let pendingDrag = null;
  let lastMeta = null;
  let size = [1, 1]; // the size this page asks for
  const drawn = []; // [seq, time] of drawn frames, for waitSeq
  const history = []; // per frame: stages
  const frameTimes = [];
  const stageColours = {};

  // -- Vectors -------------------------------------------------------------------------
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [
    a[1] * b[2] - a[2] * b[1],
    a[2] * b[0] - a[0] * b[2],
    a[0] * b[1] - a[1] * b[0],
  ];
  const len = (a) => Math.hypot(a[0], a[1], a[2]);
  const unit = (a) => mul(a, 1 / (len(a) || 1));
  // Rodrigues: v rotated by angle about unit axis k.
  const rotate = (v, k, angle) => {
    const c = Math.cos(angle), s = Math.sin(angle);
    return add(add(mul(v, c), mul(cross(k, v), s)), mul(k, dot(k, v) * (1 - c)));
  };

  function basis() {
    const forward = unit(sub(camera.look_at, camera.position));
    const right = unit(cross(forward, camera.up));
    const up = cross(right, forward);
    return { forward, right, up, distance: len(sub(camera.look_at, camera.position)) };
  }

  // -- Camera moves --------------------------------------------------------------------
  function orbit(dx, dy) {
    const worldUp = unit(camera.up);
    let offset = sub(camera.position, camera.look_at);
    offset = rotate(offset, worldUp, -dx);
    const right = unit(cross(mul(offset, -1), worldUp));
    const angle = Math.acos(Math.max(-1, Math.min(1, dot(unit(offset), worldUp))));
    const pitch = Math.max(0.01 - angle, Math.min(Math.PI - 0.01 - angle, dy));
    offset = rotate(offset, right, pitch);
    camera.position = add(camera.look_at, offset);
    cameraChanged();
  }

  function pan(dxPixels, dyPixels) {
    const b = basis();
    const scale = (2 * b.distance * Math.tan((camera.fov * Math.PI) / 360)) / view.clientHeight;
    const move = add(mul(b.right, -dxPixels * scale), mul(b.up, dyPixels * scale));
    camera.position = add(camera.position, move);
    camera.look_at = add(camera.look_at, move);
    cameraChanged();
  }

  function zoom(factor) {
    const offset = sub(camera.position, camera.look_at);
    const d = Math.max(len(offset) * factor, 1e-3);
    camera.position = add(camera.look_at, mul(unit(offset), d));
    cameraChanged();
  }

  function fly(forward, rightward, upward) {
    const b = basis();
    const step = Math.max(b.distance, 0.1);
    const move = add(add(mul(b.forward, forward * step), mul(b.right, rightward * step)),
      mul(unit(camera.up), upward * step));
    camera.position = add(camera.position, move);
    camera.look_at = add(camera.look_at, move);
    cameraChanged();
  }

  function cameraChanged() {
    pendingCamera = true;
    schedule();
  }

  // -- Messages to the server ----------------------------------------------------------
  function send(message) {
    if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
  }

  let scheduled = false;
  function schedule() {
    if (scheduled) return;
    scheduled = true;
    requestAnimationFrame(flush);
  }

  // Sends the newest camera and drag positions, once per animation frame.
  function flush() {
    scheduled = false;
    if (pendingCamera && camera) {
      pendingCamera = false;
      send({
        type: "camera",
        seq: ++seq,
        camera: { position: camera.position, look_at: camera.look_at, up: camera.up, fov: camera.fov },
      });
    }
    if (pendingDrag) {
      send({ type: "drag", x: pendingDrag[0], y: pendingDrag[1], seq: ++seq });
      pendingDrag = null;
    }
    if (keys.size) {
      flyKeys();
      schedule();
    }
  }

  function sendSetting(name, value) {
    send({ type: "settings", settings: { [name]: value } });
  }

  // -- Frames from the server ----------------------------------------------------------
  const decoder = new TextDecoder();

  async function onFrame(buffer) {
    const head = new DataView(buffer).getUint32(0);
    const meta = JSON.parse(decoder.decode(new Uint8Array(buffer, 4, head)));
    const blob = new Blob([new Uint8Array(buffer, 4 + head)], { type: "image/png" });
    let bitmap;
    try {
      bitmap = await createImageBitmap(blob);
    } catch (e) {
      showError(`could not decode frame ${meta.id}: ${e}`);
      send({ type: "ack", frame: meta.id });
      return;
    }
    if (canvas.width !== bitmap.width || canvas.height !== bitmap.height) {
      canvas.width = bitmap.width;
      canvas.height = bitmap.height;
    }
    ctx.drawImage(bitmap, 0, 0);
    bitmap.close();
    send({ type: "ack", frame: meta.id });
    const now = performance.now();
    if (meta.seq != null) drawn.push([meta.seq, now]);
    if (drawn.length > 200) drawn.splice(0, drawn.length - 200);
    frameTimes.push(now);
    while (frameTimes.length && now - frameTimes[0] > 2000) frameTimes.shift();
    lastMeta = meta;
    giViewer.frames += 1;
    const { doing, width, height, progressive, passes, seq: frameSeq } = meta;
    const { total_seconds } = meta;
    giViewer.metas.push({ doing, width, height, progressive, passes, seq: frameSeq, total_seconds });
    if (giViewer.metas.length > 200) giViewer.metas.splice(0, giViewer.metas.length - 200);
    showMeta(meta);
    for (const waiter of waiters.splice(0)) waiter();
  }

  function showMeta(meta) {
    const fps = frameTimes.length > 1
      ? ((frameTimes.length - 1) * 1000) / (frameTimes[frameTimes.length - 1] - frameTimes[0])
      : 0;
    $("timing").textContent =
      `${meta.method} ${meta.width}×${meta.height} · ${(meta.total_seconds * 1000).toFixed(1)} ms · ${fps.toFixed(1)} fps`;
    $("passes").textContent = meta.progressive ? String(meta.passes) : "–";
    $("doing").textContent = meta.doing || "";
    $("photons").textContent = meta.photons_stored ? meta.photons_stored.toLocaleString("en") : "–";
    history.push(meta.stages);
    if (history.length > 60) history.shift();
    drawChart();
    drawMarks(meta.lights || []);
  }

  function colour(stage) {
    if (!(stage in stageColours)) {
      const hue = (Object.keys(stageColours).length * 137.5) % 360;
      stageColours[stage] = `hsl(${hue}, 65%, 58%)`;
    }
    return stageColours[stage];
  }

  // Frame time by stage, one stacked bar per frame (newest right), scaled to the slowest.
  function drawChart() {
    const c = chart.getContext("2d");
    c.clearRect(0, 0, chart.width, chart.height);
    // Scaled to twice the median frame, so that one slow frame (the first, a new
    // renderer) does not flatten the rest; taller bars are cut.
    const totals = history.map((st) => st.reduce((s, [, t]) => s + t, 0));
    const sorted = [...totals].sort((a, b) => a - b);
    const top = Math.max(2 * sorted[Math.floor(sorted.length / 2)] || 0, 1e-3);
    const w = chart.width / 60;
    history.forEach((stages, i) => {
      let y = chart.height;
      for (const [name, t] of stages) {
        const h = Math.min((t / top) * (chart.height - 10), y - 10);
        c.fillStyle = colour(name);
        c.fillRect(i * w, y - h, Math.max(w - 1, 1), h);
        y -= h;
      }
    });
    c.fillStyle = "#ccc";
    c.font = "10px monospace";
    c.fillText(`${(top * 1000).toFixed(0)} ms`, 2, 9);
    // The legend names the five slowest stages of the last frame and sums the rest.
    const last = [...(history[history.length - 1] || [])].sort((a, b) => b[1] - a[1]);
    const shown = last.slice(0, 5);
    const rest = last.slice(5).reduce((s, [, t]) => s + t, 0);
    if (rest > 0) shown.push(["other", rest]);
    $("legend").replaceChildren(...shown.map(([name, t]) => {
      const span = document.createElement("span");
      const swatch = document.createElement("i");
      swatch.style.background = colour(name);
      span.append(swatch, `${name} ${(t * 1000).toFixed(1)}`);
      return span;
    }));
  }

  // Where the image lies inside the canvas box (object-fit: contain).
  function contentRect() {
    const bw = view.clientWidth, bh = view.clientHeight;
    const aspect = canvas.width / canvas.height;
    let w = bw, h = bw / aspect;
    if (h > bh) { h = bh; w = bh * aspect; }
    return { x: (bw - w) / 2, y: (bh - h) / 2, w, h };
  }

  function imagePosition(event) {
    const box = view.getBoundingClientRect();
    const r = contentRect();
    const x = (event.clientX - box.left - r.x) / r.w;
    const y = (event.clientY - box.top - r.y) / r.h;
    return [Math.min(Math.max(x, 0), 1), Math.min(Math.max(y, 0), 1)];
  }

  // Lights are points the renderer does not draw: mark them so they can be picked.
  function drawMarks(lights) {
    const dpr = window.devicePixelRatio || 1;
    marks.width = view.clientWidth * dpr;
    marks.height = view.clientHeight * dpr;
    const c = marks.getContext("2d");
    c.scale(dpr, dpr);
    const r = contentRect();
    c.strokeStyle = "rgba(255, 220, 120, 0.9)";
    c.lineWidth = 1.5;
    for (const p of lights) {
      if (!p) continue;
      c.beginPath();
      c.arc(r.x + p[0] * r.w, r.y + p[1] * r.h, 7, 0, 2 * Math.PI);
      c.stroke();
    }
  }

  // -- Messages from the server --------------------------------------------------------
  function onMessage(message) {
    if (message.type === "hello") {
      clientId = message.client;
      applyState(message, true);
      requestSize();
    } else if (message.type === "state") {
      applyState(message, message.source !== clientId);
    } else if (message.type === "error") {
      showError(message.message);
      // A change the server refused: back to the panel values and camera it has.
      if (server) applyState(server, String(message.field || "").startsWith("camera"));
    } else if (message.type === "picked") {
      giViewer.picked = message;
      moving = message.kind ? message : null;
      if (!message.kind) showStatus("nothing to move here", 1500);
      else showStatus(message.kind === "light" ? `light ${message.index}` : `object ${message.name ?? message.index}`, 1500);
    }
  }

  function applyState(state, takeCamera) {
    server = state;
    giViewer.state = state;
    if (takeCamera || !camera) camera = structuredClone(state.camera);
    $("scene").textContent = state.scene;
    fillSelect($("method"), state.methods, state.method);
    fillSelect($("tonemap"), state.tonemaps, state.display.tonemap);
    if (state.environment) {
      fillSelect($("env-source"), state.environment.choices, state.environment.source);
      setInput($("env-strength"), state.environment.strength);
      if (document.activeElement !== $("env-mode")) $("env-mode").value = state.environment.mode;
    }
    fillSelect($("aov"), state.aovs, state.display.aov, (n) => (n === "radiance" ? "beauty" : n));
    // The option table's rows for this method (gi.options_table): choices, defaults, docs; an
    // option the method does not take is disabled (kept for the methods that do).
    const options = state.options || {};
    const est = options.estimator && options.estimator.choices ? options.estimator.choices : [];
    $("estimators").replaceChildren(...est.map((n) => new Option(n, n)));
    for (const [id, name] of [["estimator", "estimator"], ["photons-setting", "photons"], ["subsample", "subsample"]]) {
      const input = $(id);
      const row = options[name];
      input.disabled = !row;
      input.placeholder = row ? `default ${row.default ?? "auto"}` : "not for this method";
      input.title = row ? `${row.doc} (${row.range})` : "";
      setInput(input, state.settings[name]);
    }
    if (document.activeElement !== $("exposure")) {
      $("exposure").value = state.display.exposure;
      $("exposure-value").textContent = Number(state.display.exposure).toFixed(1);
    }
    $("pause").setAttribute("aria-pressed", String(state.paused));
    $("pause").textContent = state.paused ? "Resume" : "Pause";
    $("progressive-note").textContent = state.progressive_error
      ? `no refinement: ${state.progressive_error}`
      : "moving: quick frames (fewer samples; CPU methods at half size) · still: refines by itself";
    $("adapter").textContent = state.adapter;
  }

  function fillSelect(select, names, current, label = (n) => n) {
    const same = select.options.length === names.length &&
      names.every((n, i) => select.options[i].value === n);
    if (!same) select.replaceChildren(...names.map((n) => new Option(label(n), n)));
    if (document.activeElement !== select) select.value = current;
  }

  function setInput(input, value) {
    if (document.activeElement !== input) input.value = value == null ? "" : String(value);
  }

  let errorTimer = null;
  function showError(text) {
    $("error-text").textContent = text;
    $("error").hidden = false;
    clearTimeout(errorTimer);
    errorTimer = setTimeout(() => { $("error").hidden = true; }, 10000);
  }

  let statusTimer = null;
  function showStatus(text, ms) {
    $("status").textContent = text;
    $("status").hidden = false;
    clearTimeout(statusTimer);
    if (ms) statusTimer = setTimeout(() => { $("status").hidden = true; }, ms);
  }

  // The render keeps the pixel count the server started with and takes the view's aspect.
  // Every tab shares one renderer: the tab last resized or used sets the size, and the
  // others show its frames letterboxed until they are used.
  function requestSize() {
    if (!server) return;
    const [w0, h0] = server.pixels;
    const aspect = view.clientWidth / Math.max(view.clientHeight, 1);
    if (!(aspect > 0)) return;
    const w = Math.max(1, Math.min(4096, Math.round(Math.sqrt(w0 * h0 * aspect))));
    const h = Math.max(1, Math.min(4096, Math.round(w / aspect)));
    size = [w, h];
    if (w !== server.size[0] || h !== server.size[1]) send({ type: "resize", width: w, height: h });
  }

  function connect() {
    socket = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
    socket.binaryType = "arraybuffer";
    socket.onopen = () => { $("status").hidden = true; };
    socket.onmessage = (event) => {
      if (typeof event.data === "string") onMessage(JSON.parse(event.data));
      else onFrame(event.data);
    };
    socket.onclose = () => {
      showStatus("disconnected: reconnecting…");
      setTimeout(connect, 1000);
    };
  }

  // -- Input ---------------------------------------------------------------------------
  let drag = null; // {mode: "orbit" | "pan" | "move", x, y}
  let moving = null;
  const pointers = new Map();
  let pinch = null;

  view.addEventListener("contextmenu", (e) => e.preventDefault());
  view.addEventListener("pointerdown", (e) => {
    if (e.target !== canvas && e.target !== view) return; // the error box's button
    view.focus();
    requestSize();
    view.setPointerCapture(e.pointerId);
    pointers.set(e.pointerId, [e.clientX, e.clientY]);
    if (pointers.size === 2) {
      drag = null;
      pinch = pinchState();
      return;
    }
    const moveTool = $("move").getAttribute("aria-pressed") === "true";
    let mode = "orbit";
    if (e.ctrlKey || e.altKey || moveTool) mode = "move";
    else if (e.shiftKey || e.button === 2 || e.button === 1) mode = "pan";
    drag = { mode, x: e.clientX, y: e.clientY };
    if (mode === "move") {
      const [x, y] = imagePosition(e);
      moving = null;
      send({ type: "pick", x, y });
    }
  });
  view.addEventListener("pointermove", (e) => {
    if (!pointers.has(e.pointerId)) return;
    pointers.set(e.pointerId, [e.clientX, e.clientY]);
    if (pinch && pointers.size === 2) {
      const now = pinchState();
      zoom(pinch.spread / Math.max(now.spread, 1));
      pan(now.x - pinch.x, now.y - pinch.y);
      pinch = now;
      return;
    }
    if (!drag || !camera) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.mode === "orbit") orbit((dx / view.clientHeight) * Math.PI, (dy / view.clientHeight) * Math.PI);
    else if (drag.mode === "pan") pan(dx, dy);
    else if (moving) {
      pendingDrag = imagePosition(e);
      schedule();
    }
  });
  const release = (e) => {
    pointers.delete(e.pointerId);
    if (pointers.size < 2) pinch = null;
    if (drag && drag.mode === "move" && moving) {
      flush(); // the last position before the drop
      send({ type: "drop" });
    }
    drag = null;
    moving = null;
  };
  view.addEventListener("pointerup", release);
  view.addEventListener("pointercancel", release);

  function pinchState() {
    const [a, b] = [...pointers.values()];
    return { x: (a[0] + b[0]) / 2, y: (a[1] + b[1]) / 2, spread: Math.hypot(a[0] - b[0], a[1] - b[1]) };
  }

  view.addEventListener("wheel", (e) => {
    e.preventDefault();
    if (camera) zoom(Math.exp(e.deltaY * 0.001));
  }, { passive: false });

  const keys = new Set();
  const FLY = { KeyW: [1, 0, 0], KeyS: [-1, 0, 0], KeyA: [0, -1, 0], KeyD: [0, 1, 0], KeyQ: [0, 0, -1], KeyE: [0, 0, 1] };
  let lastFly = 0;
  function flyKeys() {
    const now = performance.now();
    const dt = Math.min((now - lastFly) / 1000, 0.1);
    lastFly = now;
    let f = 0, r = 0, u = 0;
    for (const k of keys) {
      if (FLY[k]) { f += FLY[k][0]; r += FLY[k][1]; u += FLY[k][2]; }
    }
    if (f || r || u) fly(f * dt * 0.5, r * dt * 0.5, u * dt * 0.5);
  }

  window.addEventListener("keydown", (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    if (!camera) return;
    requestSize();
    if (FLY[e.code]) {
      if (!keys.size) lastFly = performance.now();
      keys.add(e.code);
      schedule();
    } else if (e.code === "ArrowLeft") orbit(-0.05, 0);
    else if (e.code === "ArrowRight") orbit(0.05, 0);
    else if (e.code === "ArrowUp") orbit(0, -0.05);
    else if (e.code === "ArrowDown") orbit(0, 0.05);
    else if (e.key === "+" || e.key === "=") zoom(0.9);
    else if (e.key === "-") zoom(1 / 0.9);
    else if (e.code === "KeyR") send({ type: "reset_view", seq: ++seq });
    else if (e.code === "KeyM") $("move").click();
    else if (e.code === "Space") $("pause").click();
    else return;
    e.preventDefault();
  });
  window.addEventListener("keyup", (e) => keys.delete(e.code));
  window.addEventListener("blur", () => keys.clear());

  // -- Panel ---------------------------------------------------------------------------
  $("method").addEventListener("change", (e) => sendSetting("method", e.target.value));
  $("estimator").addEventListener("change", (e) => sendSetting("estimator", e.target.value || null));
  for (const [id, name] of [["photons-setting", "photons"], ["subsample", "subsample"]]) {
    $(id).addEventListener("change", (e) => {
      const text = e.target.value.trim();
      const n = Number(text);
      if (text === "") sendSetting(name, null);
      else if (Number.isInteger(n)) sendSetting(name, n);
      else showError(`${name}: expected a whole number, got ${text}`);
    });
  }
  $("exposure").addEventListener("input", (e) => {
    $("exposure-value").textContent = Number(e.target.value).toFixed(1);
    send({ type: "display", exposure: Number(e.target.value) });
  });
  $("tonemap").addEventListener("change", (e) => send({ type: "display", tonemap: e.target.value }));
  // The environment light (gi.lighting): the scene's own, or the built-in sky.
  function sendEnvironment() {
    const strength = Number($("env-strength").value);
    if (!(strength >= 0)) return showError("environment strength: expected a number ≥ 0");
    send({
      type: "environment", source: $("env-source").value, strength,
      rotation: Number($("env-rotation").value), mode: $("env-mode").value, seq: ++seq,
    });
  }
  ["env-source", "env-strength", "env-mode"].forEach((id) => $(id).addEventListener("change", sendEnvironment));
  $("env-rotation").addEventListener("input", (e) => {
    $("env-rotation-value").textContent = e.target.value;
  });
  $("env-rotation").addEventListener("change", sendEnvironment);
  $("aov").addEventListener("change", (e) => send({ type: "display", aov: e.target.value }));
  $("pause").addEventListener("click", () => send({ type: "pause", paused: !(server && server.paused) }));
  $("reset").addEventListener("click", () => send({ type: "reset_view", seq: ++seq }));
  $("move").addEventListener("click", () => {
    const on = $("move").getAttribute("aria-pressed") !== "true";
    $("move").setAttribute("aria-pressed", String(on));
    view.classList.toggle("moving", on);
  });
  $("error-close").addEventListener("click", () => { $("error").hidden = true; });
  window.addEventListener("focus", requestSize);

  let resizeTimer = null;
  window.addEventListener("resize", () => {
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(() => { requestSize(); if (lastMeta) drawMarks(lastMeta.lights || []); }, 150);
  });

  // -- For scripts and tests -----------------------------------------------------------
  const waiters = [];
  const giViewer = {
    frames: 0,
    // The last 200 frames' meta (doing, size, progressive, passes, seq, render seconds),
    // oldest first: a
    // frame may be replaced by the next before a script looks at giViewer.meta.
    metas: [],
    state: null,
    get meta() { return lastMeta; },
    get camera() { return camera; },
    // The size the page asked for (the view's aspect at the server's pixel count).
    get size() { return size; },
    // The seq of the last change this page sent.
    get seq() { return seq; },
    picked: null,
    // Page (client) coordinates of image position (x, y) in [0, 1].
    toClient(x, y) {
      const box = view.getBoundingClientRect();
      const r = contentRect();
      return [box.left + r.x + x * r.w, box.top + r.y + y * r.h];
    },
    // Sends raw text (tests: a malformed message must come back as an error).
    sendRaw(text) { socket.send(text); },
    // Orbits by (dx, dy) radians now and returns the seq of the camera message sent.
    orbit(dx, dy) {
      orbit(dx, dy);
      flush();
      return seq;
    },
    // Resolves with performance.now() once a frame showing change `s` has been drawn.
    waitSeq(s) {
      return new Promise((resolve) => {
        const check = () => {
          const hit = drawn.find(([q]) => q >= s);
          if (hit) resolve(hit[1]);
          else waiters.push(check);
        };
        check();
      });
    },
  };
  window.giViewer = giViewer;

  connect();
})();
