// The scene page (scene.html, issue 40) in a real headless Chromium, driven by
// playwright-core: opened from disk with every non-file request refused, it must
// draw a first frame without a console error, draw a canvas that is not blank (pixel
// variance), draw another frame when the time slider moves, and, for the `bridge`
// scene, show every switching method entering the map-aided mode under the deck and
// leaving it again (read from the page's own decoded data). Screenshots of each scene
// go to OUT_DIR (and to DOCS_DIR when given: the README's pictures).
//
// usage: node .ci/scene-page.cjs PAGE OUT_DIR [DOCS_DIR]
// env:   FATHOM_NODE_MODULES (where playwright-core is installed), CHROMIUM (binary)
'use strict';
const path = require('path');
const fs = require('fs');
const modules = path.resolve(process.env.FATHOM_NODE_MODULES || 'target/browser-test/node_modules');
const { chromium } = require(path.join(modules, 'playwright-core'));

const [pagePath, outDir, docsDir] = process.argv.slice(2);
if (!pagePath || !outDir) {
  console.error('usage: node .ci/scene-page.cjs PAGE OUT_DIR [DOCS_DIR]');
  process.exit(2);
}
const MIN_VARIANCE = 20; // luminance variance (0..255 scale) of a drawn scene; a blank canvas has 0

function fail(msg) { throw new Error(msg); }

// Upward ray (NED: -down) from p against the mesh; true when a triangle is above.
function underMesh(mesh, p) {
  const v = mesh.v, idx = mesh.i;
  const d = [0, 0, -1];
  for (let t = 0; t < idx.length; t += 3) {
    const a = [v[3 * idx[t]], v[3 * idx[t] + 1], v[3 * idx[t] + 2]];
    const b = [v[3 * idx[t + 1]], v[3 * idx[t + 1] + 1], v[3 * idx[t + 1] + 2]];
    const c = [v[3 * idx[t + 2]], v[3 * idx[t + 2] + 1], v[3 * idx[t + 2] + 2]];
    const e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    const h = [d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]];
    const det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
    if (Math.abs(det) < 1e-12) continue;
    const f = 1 / det, s = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    const u = f * (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]);
    if (u < 0 || u > 1) continue;
    const q = [s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]];
    const w = f * (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]);
    if (w < 0 || u + w > 1) continue;
    if (f * (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) > 0.5) return true;
  }
  return false;
}

// The bridge scene's modes, read from the page's own data.
function checkBridge(scene) {
  const at = (k) => [scene.truth[3 * k], scene.truth[3 * k + 1], scene.truth[3 * k + 2]];
  const n = scene.times.length;
  const switching = scene.methods.filter((m) => m.modes.length > 1 && m.modes[1] === 'map-aided');
  if (!switching.length) fail('bridge: no switching method in the page');
  if (underMesh(scene.mesh, at(0)) || underMesh(scene.mesh, at(n - 1))) fail('bridge: the flight starts or ends under the deck');
  const lines = [];
  for (const m of switching) {
    const first = m.mode.indexOf(1), last = m.mode.lastIndexOf(1);
    if (first <= 0) fail(`bridge/${m.name}: never enters the map-aided mode after GPS/INS`);
    if (last >= n - 1) fail(`bridge/${m.name}: does not return to GPS/INS`);
    let under = 0, inMap = 0;
    for (let k = 0; k < n; k++) if (m.mode[k] === 1) { inMap++; if (underMesh(scene.mesh, at(k))) under++; }
    if (under === 0) fail(`bridge/${m.name}: map-aided at no epoch under the deck`);
    lines.push(`${m.name}: GPS/INS -> map-aided at t=${scene.times[first].toFixed(1)} s, back at t=${scene.times[last + 1].toFixed(1)} s; ` +
      `${under} of ${inMap} map-aided epochs under the deck`);
  }
  return lines;
}

async function main() {
  fs.mkdirSync(outDir, { recursive: true });
  const userData = fs.mkdtempSync(path.join(require('os').tmpdir(), 'fathom-chromium-'));
  const browser = await chromium.launchPersistentContext(userData, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    viewport: { width: 1200, height: 750 },
    args: ['--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update',
      '--disable-sync'],
  });
  const errors = [], fetched = [];
  try {
    const page = await browser.newPage();
    // Errors fail the test; warnings are printed (the GL driver warns about the
    // pixel read-back this test itself does).
    page.on('console', (m) => {
      if (m.type() === 'error') errors.push(`console error: ${m.text()}`);
      else if (m.type() === 'warning' && !/GPU stall due to ReadPixels/.test(m.text())) console.log(`console warning: ${m.text()}`);
    });
    page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
    await page.route('**/*', (r) => {
      const url = r.request().url();
      if (url.startsWith('file:')) return r.continue();
      fetched.push(url);
      return r.abort();
    });
    await page.goto('file://' + path.resolve(pagePath));
    await page.waitForFunction(() => window.FATHOM_SCENE && window.FATHOM_SCENE.frames() > 0, null, { timeout: 60000 });
    const stats = () => page.evaluate(() => {
      const gl = document.querySelector('#app canvas');
      const c = document.createElement('canvas');
      c.width = gl.width; c.height = gl.height;
      const g = c.getContext('2d');
      g.drawImage(gl, 0, 0);
      const px = g.getImageData(0, 0, c.width, c.height).data;
      let s = 0, s2 = 0, n = 0, hash = 0;
      for (let i = 0; i < px.length; i += 4) {
        const y = 0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2];
        s += y; s2 += y * y; n++;
        hash = (hash * 31 + px[i] + 7 * px[i + 1] + 13 * px[i + 2]) % 1000000007;
      }
      return { variance: s2 / n - (s / n) * (s / n), hash, frames: window.FATHOM_SCENE.frames() };
    });
    const nextFrame = async (before) => {
      await page.waitForFunction((f) => window.FATHOM_SCENE.frames() > f, before, { timeout: 30000 });
    };
    const names = await page.evaluate(() => window.FATHOM_SCENE.scenes.map((s) => s.name));
    const report = [];
    for (let k = 0; k < names.length; k++) {
      const name = names[k];
      let f = await page.evaluate(() => window.FATHOM_SCENE.frames());
      await page.selectOption('#sceneSel', String(k));
      await nextFrame(f);
      const data = await page.evaluate((i) => {
        const s = window.FATHOM_SCENE.scenes[i];
        const plain = (a) => Array.from(a);
        return {
          times: plain(s.times), truth: plain(s.truth), mesh: { v: plain(s.mesh.v), i: plain(s.mesh.i) },
          methods: s.methods.map((m) => ({ name: m.name, modes: m.modes, mode: plain(m.mode) })),
        };
      }, k);
      const n = data.times.length;
      // An epoch to show: the first map-aided one of a switching method, else mid-flight.
      let show = Math.floor(n / 2);
      for (const m of data.methods) { const j = m.mode.indexOf(1); if (j > 0) { show = Math.min(n - 1, j + 5); break; } }
      const setSlider = async (e) => {
        const before = await page.evaluate(() => window.FATHOM_SCENE.frames());
        await page.locator('#slider').evaluate((el, v) => { el.value = String(v); el.dispatchEvent(new Event('input', { bubbles: true })); }, e);
        await nextFrame(before);
      };
      await setSlider(0);
      const a = await stats();
      await setSlider(show);
      const b = await stats();
      if (!(a.variance > MIN_VARIANCE && b.variance > MIN_VARIANCE)) fail(`${name}: canvas looks blank (variance ${a.variance.toFixed(1)}, ${b.variance.toFixed(1)})`);
      if (a.hash === b.hash) fail(`${name}: moving the slider from epoch 0 to ${show} did not change the frame`);
      const status = await page.evaluate(() => window.FATHOM_SCENE.statusText());
      if (!/error [0-9.]+ m, mode /.test(status)) fail(`${name}: status text without error and mode: ${status}`);
      const shot = path.join(outDir, `scene_${name}.png`);
      await page.screenshot({ path: shot });
      if (docsDir) { fs.mkdirSync(docsDir, { recursive: true }); fs.copyFileSync(shot, path.join(docsDir, `scene_${name}.png`)); }
      report.push(`${name}: ${n} epochs, variance ${a.variance.toFixed(0)} / ${b.variance.toFixed(0)}, slider 0 -> ${show} changed the frame; status "${status.split('\n')[0]}"; ${shot}`);
      if (name === 'bridge') report.push(...checkBridge(data).map((l) => '  ' + l));
    }
    if (!names.includes('bridge')) report.push('(no bridge scene in this page: the mode check did not run)');
    if (fetched.length) fail(`the page asked for the network: ${fetched.join(', ')}`);
    if (errors.length) fail(`console errors:\n${errors.join('\n')}`);
    console.log(report.join('\n'));
  } finally {
    await browser.close();
    fs.rmSync(userData, { recursive: true, force: true });
  }
}

main().catch((e) => { console.error(`FAILED: ${e.message}`); process.exit(1); });
