// node docs/web/bench.js URL...: opens each URL in turn (an export's index.html with
// ?bench=K&reps=R, or any view) in one tab of one headless Chromium, waits for the page to finish
// (body[data-drawn] or body[data-error], at most TIMEOUT_S seconds: the environment's
// WALKVIS_BENCH_TIMEOUT, default 600) and prints one JSON line per URL, {"url", "page"}; page: from the navigation's start, the page's HTML
// received (document_ms), page.js started (script_ms), the export's bytes in hand (bytes_ms), the
// data read and checked (load_ms); parse_ms = load_ms - bytes_ms; for a view, its view cell in
// hand (cells_ms) and the view drawn (drawn_ms), the cells fetched and the order used; and the
// page's bench record.
// With WALKVIS_BENCH_SHOT=FILE.png, a screenshot of the view (640×480 from the top left) after
// each page: a ?frame view's overlay then shows real frame times.
//
// Why not `chromium --dump-dom`: it dumps at the load event, and the page finishes later (its
// sections inflate asynchronously); under --virtual-time-budget it waits, but the clock stops
// while scripts run, so every frame times 0 ms. This talks to the browser over the DevTools
// protocol on a pipe (--remote-debugging-pipe: JSON messages ended by NUL on file descriptors 3
// and 4) and reads the page's own performance.now() figures in real time.
// Exit status 0 with the line printed; 1 when the page did not finish in time or the browser failed.
'use strict';
const { spawn } = require('child_process');

const urls = process.argv.slice(2);
if (urls.length === 0) {
  console.error('usage: node docs/web/bench.js URL...');
  process.exit(2);
}
const timeoutMs = 1000 * (Number(process.env.WALKVIS_BENCH_TIMEOUT) || 600);

const browser = spawn('chromium', ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  '--window-size=700,500', '--remote-debugging-pipe', 'about:blank'], { stdio: ['ignore', 'ignore', 'ignore', 'pipe', 'pipe'] });
const toBrowser = browser.stdio[3], fromBrowser = browser.stdio[4];

let nextId = 1, pending = new Map(), inbox = '';
fromBrowser.on('data', (chunk) => {
  inbox += chunk.toString('utf8');
  for (let end = inbox.indexOf('\0'); end >= 0; end = inbox.indexOf('\0')) {
    const message = JSON.parse(inbox.slice(0, end));
    inbox = inbox.slice(end + 1);
    const waiter = pending.get(message.id);
    if (waiter) pending.delete(message.id), waiter(message);
  }
});
const send = (method, params = {}, sessionId) => new Promise((resolve, reject) => {
  const id = nextId++;
  pending.set(id, (m) => (m.error ? reject(new Error(method + ': ' + m.error.message)) : resolve(m.result)));
  toBrowser.write(JSON.stringify(sessionId ? { id, method, params, sessionId } : { id, method, params }) + '\0');
});
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function main() {
  const t0 = Date.now();
  let page;
  while (!page) {
    const { targetInfos } = await send('Target.getTargets');
    page = targetInfos.find((t) => t.type === 'page');
    if (!page) await sleep(50);
  }
  const { sessionId } = await send('Target.attachToTarget', { targetId: page.targetId, flatten: true });
  const probe = `(() => { const d = document.body ? document.body.dataset : {};
    if (!(d.drawn || d.error)) return '';
    const nav = performance.getEntriesByType('navigation')[0];
    return JSON.stringify({ load_ms: Number(d.loadMs), document_ms: nav ? nav.responseEnd : null,
      script_ms: Number(d.scriptMs), bytes_ms: Number(d.bytesMs), parse_ms: Number(d.parseMs),
      cells_ms: d.cellsMs ? Number(d.cellsMs) : null, drawn_ms: d.drawnMs ? Number(d.drawnMs) : null,
      cells_loaded: d.cellsLoaded || null, used: d.used || null, error: d.error || null,
      bench: d.bench ? JSON.parse(d.bench) : null }); })()`;
  for (const url of urls) {
    // Navigated from a started browser, so that the page's times (from its navigation's start)
    // leave out the browser's own start.
    await send('Page.navigate', { url: 'about:blank' }, sessionId);
    await send('Page.navigate', { url }, sessionId);
    const t0 = Date.now();
    for (;;) {
      await sleep(100);
      const { result } = await send('Runtime.evaluate', { expression: probe, returnByValue: true }, sessionId);
      if (result && result.value) {
        console.log(JSON.stringify({ url, page: JSON.parse(result.value) }));
        if (process.env.WALKVIS_BENCH_SHOT) {
          const clip = { x: 0, y: 0, width: 640, height: 480, scale: 1 };
          const { data } = await send('Page.captureScreenshot', { format: 'png', clip, captureBeyondViewport: true }, sessionId);
          require('fs').writeFileSync(process.env.WALKVIS_BENCH_SHOT, Buffer.from(data, 'base64'));
        }
        break;
      }
      if (Date.now() - t0 > timeoutMs) {
        console.error(url + ': the page did not finish within ' + timeoutMs / 1000 + ' s');
        return 1;
      }
    }
  }
  return 0;
}

main()
  .then((status) => { browser.kill(); process.exit(status); })
  .catch((e) => { console.error('bench.js: ' + e.message); browser.kill(); process.exit(1); });
