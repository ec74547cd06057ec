// Opens pages of the browser build (out/web/) in headless Chromium with
// WebGPU and prints, per page, its final document.title and a screenshot.
// Usage: node --experimental-websocket tools/web-check.mjs OUT_DIR QUERY...
// Serves out/web/ on 127.0.0.1 (ES modules do not load from file://), drives
// Chromium over its DevTools protocol (headless --dump-dom cannot wait for
// WebGPU), and for a QUERY that starts with "drop:" opens the page, then
// hands the named file to its file input. Prints one JSON line per page:
// {"query", "title", "screenshot", "seconds", "retries"} and, for a compare=1 page,
// "mask": its technique's mask of the first light (base64, a byte a pixel). A page whose title still
// says "loading" after TIMEOUT_S is reported as such, not waited for.
import { createServer } from 'node:http';
import { readFile, mkdtemp, writeFile } from 'node:fs/promises';
import { spawn } from 'node:child_process';
import { tmpdir } from 'node:os';
import { join, extname } from 'node:path';

const TIMEOUT_S = Number(process.env.WEB_CHECK_TIMEOUT_S || 240);
// Times a page that found no WebGPU adapter is opened again.
const GPU_RETRIES = 2;
const [outDir, ...queries] = process.argv.slice(2);
const root = 'out/web';
const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm', '.css': 'text/css' };

const server = createServer(async (req, res) => {
  const path = new URL(req.url, 'http://x').pathname;
  try {
    const body = await readFile(join(root, path === '/' ? 'index.html' : path));
    res.writeHead(200, { 'content-type': types[extname(path || '.html')] || 'text/html' });
    res.end(body);
  } catch {
    res.writeHead(404);
    res.end();
  }
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const port = server.address().port;

const profile = await mkdtemp(join(tmpdir(), 'shadowlab-chromium-'));
const extra = (process.env.CHROMIUM_FLAGS || '').split(' ').filter((f) => f);
const windowed = process.env.WEB_CHECK_XVFB === '1';
const chromium = spawn(windowed ? 'xvfb-run' : 'chromium', [...(windowed ? ['-a', 'chromium'] : ['--headless']), ...extra, '--no-sandbox', '--enable-unsafe-webgpu',
  '--remote-debugging-port=0', `--user-data-dir=${profile}`, '--window-size=1100,800', 'about:blank'],
{ stdio: process.env.WEB_CHECK_VERBOSE === '1' ? 'inherit' : 'ignore' });
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let wsUrl;
for (let i = 0; i < 100 && !wsUrl; i++) {
  await sleep(200);
  try {
    const [p] = (await readFile(join(profile, 'DevToolsActivePort'), 'utf8')).split('\n');
    const list = await (await fetch(`http://127.0.0.1:${p}/json/list`)).json();
    wsUrl = list.find((t) => t.type === 'page')?.webSocketDebuggerUrl;
  } catch { /* not up yet */ }
}
if (!wsUrl) { console.error('chromium did not start'); process.exit(2); }

const ws = new WebSocket(wsUrl);
await new Promise((r) => ws.addEventListener('open', r));
let next = 1;
const pending = new Map();
ws.addEventListener('message', (e) => {
  const m = JSON.parse(e.data);
  if (m.id && pending.has(m.id)) { pending.get(m.id)(m); pending.delete(m.id); }
  // The page's console, for whoever reads the check's output.
  if (m.method === 'Runtime.consoleAPICalled') {
    console.error('console.' + m.params.type + ': ' + m.params.args.map((a) => a.value ?? a.description).join(' '));
  }
  if (m.method === 'Log.entryAdded') {
    console.error('log.' + m.params.entry.level + ': ' + m.params.entry.text);
  }
  if (m.method === 'Runtime.exceptionThrown') {
    console.error('exception: ' + JSON.stringify(m.params.exceptionDetails.exception?.description || m.params.exceptionDetails.text));
  }
});
const send = (method, params = {}) => new Promise((r) => {
  const id = next++;
  pending.set(id, r);
  ws.send(JSON.stringify({ id, method, params }));
});
const evaluate = async (expression) => (await send('Runtime.evaluate', { expression, awaitPromise: true, returnByValue: true })).result?.result?.value;
await send('Page.enable');
await send('DOM.enable');
await send('Runtime.enable');
await send('Log.enable');

async function waitTitle(start) {
  let title = '';
  while ((Date.now() - start) / 1000 < TIMEOUT_S) {
    title = await evaluate('document.title');
    if (title && !title.includes('loading')) break;
    await sleep(250);
  }
  return title;
}

for (const [i, q] of queries.entries()) {
  const start = Date.now();
  const [drop, query] = q.startsWith('drop:') ? [q.slice(5).split('?')[0], q.slice(5).split('?')[1] || ''] : [null, q];
  const url = query.startsWith('/') ? `http://127.0.0.1:${port}${query}` : `http://127.0.0.1:${port}/?${query}`;
  let title = '';
  let retries = 0;
  for (;;) {
    await send('Page.navigate', { url });
    await sleep(300);
    title = await waitTitle(Date.now());
    // Chromium answers requestAdapter with null while its GPU process is
    // being relaunched (SwiftShader under load): the browser's state, not
    // the page's, so the page is opened again, at most GPU_RETRIES times,
    // and the report says how often.
    if (!title.includes('no WebGPU adapter') || retries >= GPU_RETRIES) break;
    retries++;
    console.error(`no WebGPU adapter for ${q}: opening it again (${retries} of ${GPU_RETRIES})`);
    await sleep(2000);
  }
  if (drop && title.startsWith('shadowlab: ok')) {
    // The file input, given the file as a user picking it would.
    const doc = await send('DOM.getDocument');
    const node = await send('DOM.querySelector', { nodeId: doc.result.root.nodeId, selector: '#file' });
    await evaluate('document.title = "shadowlab: loading …"');
    await send('DOM.setFileInputFiles', { nodeId: node.result.nodeId, files: [drop] });
    title = await waitTitle(Date.now());
  }
  // WEB_CHECK_EVAL: an expression (awaited) run once the title settles;
  // its value is the report's "eval", and the screenshot follows it.
  const evaluated = process.env.WEB_CHECK_EVAL ? await evaluate(process.env.WEB_CHECK_EVAL) : undefined;
  const shot = await send('Page.captureScreenshot', { format: 'png' });
  const screenshot = join(outDir, `page-${i}.png`);
  await writeFile(screenshot, Buffer.from(shot.result.data, 'base64'));
  const report = { query: q, title, screenshot, seconds: (Date.now() - start) / 1000, eval: evaluated, retries };
  // The technique's mask of the comparison (compare=1 pages), as base64 bytes.
  if (query.includes('compare=1') && title.startsWith('shadowlab: ok')) {
    report.mask = await evaluate('window.shadowlab.compared_mask(0)');
  }
  console.log(JSON.stringify(report));
}
ws.close();
chromium.kill();
server.close();
