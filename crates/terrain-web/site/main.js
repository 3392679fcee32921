// The page around the renderer: loads the module, the scene and its sketch, runs the animation
// frame, passes the keys, drags and touches to the viewer, shows its figures, and gives tests
// and embedding pages `window.terrain.settled()` and `window.terrain.stats()`.

const canvas = document.getElementById('view');
const message = document.getElementById('message');
const overlay = document.getElementById('overlay');
const controls = document.getElementById('controls');
const query = new URLSearchParams(location.search);
const still = query.get('still') === '1';
// `?present=copy`: frames copied into a 2D canvas, for browsers that cannot show a WebGPU one.
const present = query.get('present') || '';

function say(text) {
  message.textContent = text;
  message.hidden = false;
}

// One line for the user, and the console for whoever debugs the page.
function fail(what, e) {
  const text = `${what}: ${e && e.message ? e.message : e}`;
  say(text);
  console.error(text);
}

// Fetches `url`, showing the bytes as they arrive.
async function fetchBytes(url, label) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  const total = Number(response.headers.get('content-length')) || 0;
  const reader = response.body.getReader();
  const parts = [];
  let got = 0;
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    parts.push(value);
    got += value.length;
    const mb = (n) => (n / 1048576).toFixed(1);
    say(total ? `Loading ${label}… ${mb(got)} of ${mb(total)} MB` : `Loading ${label}… ${mb(got)} MB`);
  }
  const bytes = new Uint8Array(got);
  let at = 0;
  for (const p of parts) {
    bytes.set(p, at);
    at += p.length;
  }
  return bytes;
}

// The canvas's size in device pixels: the scene's own in a still, the window's otherwise.
function fit(site) {
  if (still) {
    canvas.width = site.width;
    canvas.height = site.height;
    return;
  }
  const dpr = window.devicePixelRatio || 1;
  canvas.width = Math.max(1, Math.floor(canvas.clientWidth * dpr));
  canvas.height = Math.max(1, Math.floor(canvas.clientHeight * dpr));
}

function button(label, title, onclick) {
  const b = document.createElement('button');
  b.textContent = label;
  b.title = title;
  b.addEventListener('click', () => { onclick(); canvas.focus(); });
  controls.appendChild(b);
  return b;
}

async function main() {
  if (still) document.body.classList.add('still');
  if (!navigator.gpu) {
    say('This browser has no WebGPU, which the terrain needs. Chrome and Edge 113 or later, '
      + 'Safari 26 or Firefox 141 or later have it; on Linux, Chrome needs '
      + '--enable-unsafe-webgpu.');
    return;
  }
  say('Loading the renderer…');
  // Loaded here, not imported above, so that a browser without WebGPU or a module that fails
  // to load gets the page's message.
  const { default: init, Viewer } = await import('./pkg/terrain_web.js');
  await init({ module_or_path: new URL('pkg/terrain_web_bg.wasm', import.meta.url) });
  const site = await (await fetch('site.json')).json();
  const sceneText = await (await fetch(site.scene)).text();
  const sketch = site.sketch ? await fetchBytes(site.sketch, 'the sketch') : new Uint8Array();
  say('Preparing the terrain…');
  fit(site);
  const viewer = await Viewer.create(canvas, sceneText, sketch, site.mode || '', still, present);
  // The adapter as the browser describes it (wgpu sees only its description, often empty).
  const info = (await navigator.gpu.requestAdapter())?.info;
  const adapter = [info?.vendor, info?.architecture, info?.description]
    .filter((s) => s).join(' ') || viewer.stats().adapter;

  // The hooks (names in the design): a Promise per settled() call, resolved after the frame
  // the GPU finished; stats() as the viewer reports them.
  let waiting = [];
  window.terrain = {
    settled: () => new Promise((resolve) => waiting.push(resolve)),
    stats: () => ({ ...viewer.stats(), adapter }),
    // The next frame's pixels (RGBA, rows top first), drawn even when a still is held.
    capture: () => viewer.capture(),
    setMode: (name) => { viewer.set_mode(name); mark(); },
    setView: (name) => { viewer.set_view(name); mark(); },
  };

  const modeButtons = new Map();
  for (const { name, label, key } of viewer.modes()) {
    modeButtons.set(name, button(label, `${label} (key ${key})`, () => window.terrain.setMode(name)));
  }
  const wire = button('Wireframe', 'the mesh over the picture (key V)', () =>
    window.terrain.setView(viewer.view() === 'wireframe' ? 'shaded' : 'wireframe'));
  function mark() {
    const chosen = viewer.coming() || viewer.mode();
    for (const [name, b] of modeButtons) b.setAttribute('aria-pressed', String(name === chosen));
    wire.setAttribute('aria-pressed', String(viewer.view() === 'wireframe'));
  }
  mark();

  // Input, as `terrain view` takes it.
  let drag = null;
  canvas.addEventListener('pointerdown', (e) => {
    if (e.pointerType === 'touch') return;
    drag = { x: e.clientX, y: e.clientY };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    viewer.look(e.clientX - drag.x, e.clientY - drag.y);
    drag = { x: e.clientX, y: e.clientY };
  });
  canvas.addEventListener('pointerup', () => { drag = null; });
  // Touch: one finger looks, two fingers spread to fly forward and pinch to fly back.
  let touches = null;
  const spread = (t) => Math.hypot(t[0].clientX - t[1].clientX, t[0].clientY - t[1].clientY);
  canvas.addEventListener('touchstart', (e) => { e.preventDefault(); touches = [...e.touches]; }, { passive: false });
  canvas.addEventListener('touchmove', (e) => {
    e.preventDefault();
    const now = [...e.touches];
    if (touches && now.length === 1 && touches.length === 1) {
      viewer.look(now[0].clientX - touches[0].clientX, now[0].clientY - touches[0].clientY);
    } else if (touches && now.length === 2 && touches.length === 2) {
      viewer.nudge((spread(now) - spread(touches)) / 10);
    }
    touches = now;
  }, { passive: false });
  canvas.addEventListener('touchend', (e) => { touches = [...e.touches]; viewer.nudge(0); });
  window.addEventListener('keydown', (e) => {
    if (e.repeat) return;
    const row = [...modeButtons.keys()].find((_, i) => e.code === `Digit${viewer.modes()[i].key}`);
    if (row) {
      window.terrain.setMode(row);
    } else if (e.code === 'KeyV') {
      wire.click();
    } else {
      viewer.key(e.code, true);
    }
    if (e.code.startsWith('Arrow') || e.code.startsWith('Page')) e.preventDefault();
  });
  window.addEventListener('keyup', (e) => viewer.key(e.code, false));
  window.addEventListener('blur', () => {
    for (const code of ['KeyW', 'KeyA', 'KeyS', 'KeyD', 'KeyE', 'KeyQ', 'ShiftLeft', 'ShiftRight',
      'ArrowUp', 'ArrowDown', 'ArrowLeft', 'ArrowRight', 'PageUp', 'PageDown']) viewer.key(code, false);
  });
  if (!still) {
    new ResizeObserver(() => {
      fit(site);
      try {
        viewer.resize(canvas.width, canvas.height);
      } catch (e) {
        fail('The canvas could not resize', e);
      }
    }).observe(canvas);
  }

  message.hidden = true;
  overlay.hidden = false;
  controls.hidden = false;
  let shown = 0;
  function frame(now) {
    try {
      // A still is drawn once and held: the canvas keeps the frame the GPU finished.
      if (!(still && viewer.settled()) || viewer.capture_pending()) viewer.frame(now);
    } catch (e) {
      fail('The frame failed', e);
      return;
    }
    if (viewer.settled() && waiting.length) {
      const done = waiting;
      waiting = [];
      for (const resolve of done) resolve();
    }
    if (now - shown > 250) {
      shown = now;
      const s = window.terrain.stats();
      const fps = s.frame_ms ? (1000 / s.frame_ms).toFixed(1) : '–';
      const cpu = s.cpu_stage_us == null ? '–' : (s.cpu_stage_us / 1000).toFixed(2);
      const coming = s.coming ? ` · baking ${s.coming}…` : '';
      overlay.textContent = `${fps} fps · ${Number(s.triangles).toLocaleString('en')} triangles\n`
        + `CPU stage ${cpu} ms · ${s.mode}${s.view === 'shaded' ? '' : ` · ${s.view}`}${coming}\n`
        + s.adapter;
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
}

main().catch((e) => fail('The terrain could not start', e));
