// The page's controls over the lab (src/web/page.rs). Its progress is in
// document.title: "shadowlab: loading …", then "shadowlab: ok technique=…
// [mismatch=…% mae=…] fps=…" or "shadowlab: error …" (the test suite reads it).
import init, { Lab } from './shadowlab.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
// Frames timed for the FPS figure before the page reports.
const FPS_FRAMES = 10;

function setTitle(text) { document.title = 'shadowlab: ' + text; }
function status(text, error) {
  $('status').textContent = text;
  $('status').className = error ? 'error' : '';
}
function fail(e) {
  const message = String(e && e.message ? e.message : e).split('\n')[0];
  setTitle('error ' + message);
  status(message, true);
}
window.addEventListener('error', (e) => fail(e.error || e.message));
window.addEventListener('unhandledrejection', (e) => fail(e.reason));

// Navigates to the same page with the link's parameters changed.
function relink(changes) {
  const next = new URLSearchParams(location.search);
  for (const [k, v] of Object.entries(changes)) {
    if (v === null || v === '') next.delete(k); else next.set(k, v);
  }
  location.search = next.toString();
}

// The light whose technique the panel edits, or undefined for every light.
function scope() {
  return $('scope').value === '' ? undefined : Number($('scope').value);
}

function fillScope(lab) {
  $('scope').replaceChildren(new Option('every light', ''));
  for (let i = 0; i < lab.light_count(); i++) $('scope').add(new Option(`light ${i}`, String(i)));
}

function fillSelects(lab) {
  const scene = params.get('scene') || 'room';
  for (const name of JSON.parse(Lab.scenes())) {
    $('scene').add(new Option(name, name, false, name === scene));
  }
  $('scene').onchange = () => relink({ scene: $('scene').value, camera: null, eye: null, target: null });
  $('light').value = params.get('light') || '';
  $('light').onchange = () => relink({ light: $('light').value });
  fillScope(lab);
  $('scope').onchange = () => safely(() => { $('technique').value = JSON.parse(lab.parameters(scope())).technique; fillParams(lab); });
  const current = JSON.parse(lab.parameters()).technique;
  for (const t of JSON.parse(Lab.techniques())) {
    const o = new Option(t.id + (t.unavailable ? ' (not in the page)' : ''), t.id, false, t.id === current);
    o.disabled = !!t.unavailable;
    if (t.unavailable) o.title = t.unavailable;
    $('technique').add(o);
  }
  $('technique').onchange = async () => {
    try { await lab.set_technique($('technique').value, scope()); fillParams(lab); status('technique ' + $('technique').value); }
    catch (e) { status(String(e), true); }
  };
}

function input(row, lab) {
  const spec = row.spec;
  let el;
  if (spec.kind === 'bool') {
    el = document.createElement('input');
    el.type = 'checkbox';
    el.checked = row.value === 'true';
    el.onchange = () => apply(lab, spec.name, String(el.checked));
  } else if (spec.kind.choice) {
    el = document.createElement('select');
    for (const c of spec.kind.choice) el.add(new Option(c, c, false, c === row.value));
    el.onchange = () => apply(lab, spec.name, el.value);
  } else {
    el = document.createElement('input');
    el.type = 'number';
    Object.assign(el, { min: spec.min, max: spec.max, step: spec.step, value: row.value });
    el.onchange = () => apply(lab, spec.name, el.value);
  }
  el.title = spec.doc;
  return el;
}

async function apply(lab, key, value) {
  try { await lab.set_param(key, value, scope()); status(key + ' = ' + value); }
  catch (e) { status(String(e), true); }
  safely(() => fillParams(lab));
}

function fillParams(lab) {
  const body = $('params').tBodies[0];
  body.replaceChildren();
  for (const row of JSON.parse(lab.parameters(scope())).rows) {
    const tr = body.insertRow();
    tr.className = row.applies.some((a) => a) ? '' : 'inactive';
    const name = tr.insertCell();
    name.textContent = row.spec.name;
    name.title = row.spec.doc;
    tr.insertCell().append(input(row, lab));
  }
}

// One row per light: position, direction and intensity, as a scene file
// gives them (type, colour, range and cones keep their values).
function fillLights(lab) {
  const body = $('lights').tBodies[0];
  body.replaceChildren();
  JSON.parse(lab.lights()).forEach((light, i) => {
    const tr = body.insertRow();
    tr.insertCell().textContent = `${i} ${light.type}`;
    const field = (get, set) => {
      const el = document.createElement('input');
      el.value = get();
      el.size = 10;
      el.onchange = () => {
        try { set(el.value); lab.set_light(i, JSON.stringify(light)); status(`light ${i} changed`); }
        catch (e) { status(String(e), true); fillLights(lab); }
      };
      tr.insertCell().append(el);
    };
    const vec = (v) => v.map((c) => +c.toFixed(3)).join(',');
    const parse = (t) => t.split(',').map(Number);
    field(() => vec(light.position), (t) => { light.position = parse(t); });
    field(() => vec(light.direction), (t) => { light.direction = parse(t); });
    field(() => light.intensity, (t) => { light.intensity = Number(t); });
  });
}

// Runs a call to the lab from a control; a refusal (busy while a
// comparison runs) is shown in the status line, not raised as an error.
function safely(f) {
  try { f(); } catch (e) { status(String(e), true); }
}

function mouse(lab, canvas) {
  let drag = null;
  canvas.oncontextmenu = (e) => e.preventDefault();
  canvas.onpointerdown = (e) => { drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey }; canvas.setPointerCapture(e.pointerId); };
  canvas.onpointerup = () => { drag = null; };
  canvas.onpointermove = (e) => {
    if (!drag) return;
    const h = canvas.clientHeight || 1;
    const dx = (e.clientX - drag.x) / h, dy = (e.clientY - drag.y) / h;
    drag.x = e.clientX; drag.y = e.clientY;
    safely(() => { if (drag.pan) lab.pan(dx, dy); else lab.orbit(dx * 3, dy * 3); });
  };
  canvas.onwheel = (e) => { e.preventDefault(); safely(() => lab.zoom(Math.pow(0.9, -Math.sign(e.deltaY)))); };
}

async function openFile(lab, file) {
  status('opening ' + file.name + ' …');
  try {
    await lab.load_file(file.name, new Uint8Array(await file.arrayBuffer()));
    fillParams(lab);
    await lab.frame();
    fillScope(lab);
    fillLights(lab);
    status(file.name + ' opened');
    setTitle(`ok technique=${JSON.parse(lab.parameters()).all} file=${file.name}`);
  } catch (e) { fail(e); }
}

function files(lab, canvas) {
  $('file').onchange = () => $('file').files[0] && openFile(lab, $('file').files[0]);
  canvas.ondragover = (e) => { e.preventDefault(); canvas.classList.add('drop'); };
  canvas.ondragleave = () => canvas.classList.remove('drop');
  canvas.ondrop = (e) => {
    e.preventDefault();
    canvas.classList.remove('drop');
    if (e.dataTransfer.files[0]) openFile(lab, e.dataTransfer.files[0]);
  };
}

function describe(report) {
  const lines = [`${report.technique} on ${report.adapter}, ${report.size[0]}×${report.size[1]}`,
    `reference: ${report.reference_ms.toFixed(0)} ms on one thread (${report.reference_kernel})`];
  report.lights.forEach((m, i) => lines.push(
    `light ${i}: mismatch ${m.all.total_pct.toFixed(3)} % (false shadow ${m.all.false_shadow_pct.toFixed(3)}, false lit ${m.all.false_lit_pct.toFixed(3)}), ` +
    `MAE ${m.mean_abs_error.toFixed(4)}, interior MAE ${m.interior_mae.toFixed(4)}, graded ${m.graded_interior_pct.toFixed(2)} %`));
  return lines.join('\n');
}

// Whether this browser composites a WebGPU canvas: headless Chromium on
// SwiftShader has no shared-image backing for its swap chain and destroys
// the device at the first presented frame. Tried on a throwaway device and
// a detached canvas; where it fails, the lab draws read-back frames into a
// 2D canvas instead (src/web/present.rs).
async function webgpuCanvasWorks() {
  const adapter = await navigator.gpu?.requestAdapter();
  if (!adapter) return false;
  const device = await adapter.requestDevice();
  let lost = false;
  device.lost.then(() => { lost = true; });
  const c = document.createElement('canvas');
  c.width = c.height = 16;
  const ctx = c.getContext('webgpu');
  ctx.configure({ device, format: navigator.gpu.getPreferredCanvasFormat() });
  try {
    for (let i = 0; i < 3 && !lost; i++) {
      const e = device.createCommandEncoder();
      e.beginRenderPass({ colorAttachments: [{ view: ctx.getCurrentTexture().createView(), loadOp: 'clear', storeOp: 'store' }] }).end();
      device.queue.submit([e.finish()]);
      await new Promise((r) => requestAnimationFrame(r));
    }
    await device.queue.onSubmittedWorkDone();
    await new Promise((r) => setTimeout(r, 50));
  } catch { lost = true; }
  const works = !lost;
  device.destroy();
  return works;
}

async function main() {
  setTitle('loading …');
  if (!navigator.gpu) throw new Error('this browser has no WebGPU (navigator.gpu is missing)');
  await init();
  const canvas = $('view');
  const present = params.get('present') || ((await webgpuCanvasWorks()) ? 'webgpu' : 'readback');
  params.delete('present');
  const lab = await Lab.create(canvas, JSON.stringify([...params.entries()]), present);
  // For automation (the test suite reads compared_mask through it).
  window.shadowlab = lab;
  fillSelects(lab);
  fillParams(lab);
  fillLights(lab);
  mouse(lab, canvas);
  files(lab, canvas);
  let fps = 0, times = [];
  // Read once: a call made while an awaited one holds the lab is refused.
  const adapter = lab.adapter();
  const shown = () => `on ${adapter}, presented by ${present}`;
  const tick = async () => {
    try { await lab.frame(); } catch (e) { fail(e); return; }
    const now = performance.now();
    times.push(now);
    while (times.length > 1 && now - times[0] > 2000) times.shift();
    if (times.length > 1) fps = 1000 * (times.length - 1) / (now - times[0]);
    status(`${fps.toFixed(1)} FPS ${shown()}`);
    requestAnimationFrame(tick);
  };
  // The FPS figure: FPS_FRAMES frames, each presented.
  const start = performance.now();
  for (let i = 0; i < FPS_FRAMES; i++) {
    await lab.frame();
    await new Promise((r) => requestAnimationFrame(r));
  }
  fps = 1000 * FPS_FRAMES / (performance.now() - start);
  const technique = JSON.parse(lab.parameters()).all;
  const compare = async () => {
    status('running the reference …');
    const report = JSON.parse(await lab.compare());
    $('report').textContent = describe(report);
    return report;
  };
  $('compare').onclick = () => compare().catch(fail);
  $('image').onclick = () => safely(() => lab.show_image());
  // Each click shows the next light's mask.
  let maskLight = -1;
  $('mask').onclick = () => safely(() => {
    maskLight = (maskLight + 1) % lab.light_count();
    lab.show_mask(maskLight);
    $('mask').textContent = `Mask (light ${maskLight})`;
  });
  $('copy').onclick = async () => {
    const url = location.origin + location.pathname + '?' + lab.link();
    try { await navigator.clipboard.writeText(url); status('link copied'); }
    catch (e) { status(url); }
  };
  if (params.get('compare') === '1') {
    const report = await compare();
    const worst = report.lights.reduce((a, m) => (m.all.total_pct > a.all.total_pct ? m : a), report.lights[0]);
    const mismatch = worst ? worst.all.total_pct.toFixed(3) : '0.000';
    const mae = worst ? worst.mean_abs_error.toFixed(4) : '0.0000';
    setTitle(`ok technique=${technique} mismatch=${mismatch}% mae=${mae} fps=${fps.toFixed(1)}`);
  } else {
    setTitle(`ok technique=${technique} fps=${fps.toFixed(1)}`);
  }
  requestAnimationFrame(tick);
}

main().catch(fail);
