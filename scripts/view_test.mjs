// Loads pages written by `surfmap view` in headless Chromium (puppeteer-core) and checks
// what a user would see: no console error or uncaught exception, a canvas that is not
// blank and whose pixels change when the camera turns or a slider moves, a vertex of A
// picked with the mouse highlighting its image on B (checked against the match folder's
// files read here, and against the closed-form map that generated them), and the numbers
// on the page equal to the report's.
//
//   node scripts/view_test.mjs WORK [--screenshots DIR]   (WORK as scripts/view_test.sh fills it)
//   node scripts/view_test.mjs --bench PAGE.html…          (size and time to first frame)
//
// Prints one line per check and "N passed, M failed"; exit status 1 on any failure.
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { createRequire } from "node:module";

const require = createRequire(path.join(process.env.VIEW_TEST_DIR || "target/view-test", "package.json"));
const puppeteer = require("puppeteer-core");

const args = process.argv.slice(2);
let passed = 0, failed = 0;
function check(name, ok, detail) {
  if (ok) passed++; else failed++;
  console.log(`${ok ? "ok  " : "FAIL"} ${name}${detail ? ": " + detail : ""}`);
}

// ---------------------------------------------------------------- files read here
function readNpy(file) {
  const b = fs.readFileSync(file);
  const major = b[6];
  const headerLen = major === 1 ? b.readUInt16LE(8) : b.readUInt32LE(8);
  const start = major === 1 ? 10 : 12;
  const header = b.toString("latin1", start, start + headerLen);
  if (!header.includes("'<f8'")) throw new Error(`${file}: not little-endian float64`);
  const shape = header.match(/\(([^)]*)\)/)[1].split(",").filter((s) => s.trim()).map(Number);
  const data = new Float64Array(b.buffer.slice(b.byteOffset + start + headerLen, b.byteOffset + b.length));
  return { shape, data };
}
function readObj(file) {
  const v = [], f = [];
  for (const line of fs.readFileSync(file, "utf8").split("\n")) {
    const p = line.trim().split(/\s+/);
    if (p[0] === "v") v.push([+p[1], +p[2], +p[3]]);
    else if (p[0] === "f") {
      const ids = p.slice(1).map((s) => parseInt(s.split("/")[0], 10) - 1);
      for (let k = 1; k + 1 < ids.length; k++) f.push([ids[0], ids[k], ids[k + 1]]);
    }
  }
  return { v, f };
}
const at = (doc, p) => p.split(".").reduce((x, k) => (x === undefined || x === null ? undefined : x[k]), doc);
const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);

// ---------------------------------------------------------------- browser
async function launch() {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "surfmap-view-chromium-"));
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync",
      "--enable-unsafe-swiftshader", `--user-data-dir=${profile}`],
  });
  return { browser, profile };
}
// Screenshots are taken with multisampling, which the page leaves out on a software
// renderer unless asked (#antialias).
let hash = "";
async function open(browser, file, problems) {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 800 });
  page.on("console", (m) => { if (m.type() === "error") problems.push(`console error: ${m.text()}`); });
  page.on("pageerror", (e) => problems.push(`uncaught: ${e.message}`));
  page.on("request", (r) => { if (!r.url().startsWith("file:") && !r.url().startsWith("data:")) problems.push(`network request: ${r.url()}`); });
  await page.goto("file://" + path.resolve(file) + hash);
  await page.waitForFunction("window.surfmapView && window.surfmapView.ready", { timeout: 60000 });
  return page;
}
const snapshot = (page) => page.evaluate(() => surfmapView.snapshot());
// The centre of a panel in client coordinates.
const panelCentre = (page, name) => page.evaluate((n) => {
  const p = surfmapView.panels[n], r = document.getElementById("gl").getBoundingClientRect();
  return { x: r.left + p.px.x + p.px.w / 2, y: r.top + p.px.h / 2 };
}, name);
async function commonChecks(page, what, problems) {
  const errors = await page.evaluate(() => surfmapView.errors);
  check(`${what}: no console error, uncaught exception or network request`, problems.length === 0 && errors.length === 0,
    [...problems, ...errors].join(" | "));
  if ((await page.evaluate(() => surfmapView.data.kind)) === "table") return;
  const s = await snapshot(page);
  check(`${what}: the canvas is drawn`, s.drawnFraction > 0.1, `${(100 * s.drawnFraction).toFixed(1)} % of its pixels`);
  for (const [name, fraction] of Object.entries(s.panels))
    check(`${what}: panel ${name} is drawn`, fraction > 0.05, `${(100 * fraction).toFixed(1)} % of its pixels`);
}
async function numbersEqualReport(page, what, report) {
  const listed = await page.evaluate(() => surfmapView.data.numbers || []);
  const shown = await page.evaluate(() => Array.from(document.querySelectorAll("#numbers tr"))
    .map((tr) => ({ path: tr.dataset.path, text: tr.querySelector("td").textContent })));
  let bad = [];
  for (const n of listed) {
    const want = at(report, n.path);
    if (JSON.stringify(want) !== JSON.stringify(n.value)) bad.push(`${n.path}: page ${n.value}, report ${want}`);
    const row = shown.find((r) => r.path === n.path);
    if (!row) { bad.push(`${n.path} not shown`); continue; }
    if (typeof want === "number") {
      const v = Number(row.text);
      if (!(Math.abs(v - want) <= 1e-4 * Math.abs(want) + 1e-12)) bad.push(`${n.path}: shown ${row.text}, report ${want}`);
    }
  }
  check(`${what}: the ${listed.length} numbers on the page are the report's`, listed.length >= 8 && bad.length === 0, bad.join("; "));
}
async function dragChanges(page, what, panel) {
  const before = (await snapshot(page)).hash;
  const c = await panelCentre(page, panel);
  await page.mouse.move(c.x, c.y);
  await page.mouse.down();
  await page.mouse.move(c.x + 60, c.y + 25, { steps: 5 });
  await page.mouse.up();
  const after = (await snapshot(page)).hash;
  check(`${what}: turning the camera (mouse drag) changes the pixels`, before !== after);
}
async function sliderChanges(page, what, id, value) {
  const before = (await snapshot(page)).hash;
  await page.$eval("#" + id, (e, v) => { e.value = v; e.dispatchEvent(new Event("input")); }, String(value));
  const after = (await snapshot(page)).hash;
  check(`${what}: moving the slider ${id} to ${value} changes the pixels`, before !== after);
}

// ---------------------------------------------------------------- the pages
async function flatteningPage(browser, work, shots) {
  const problems = [], what = "flattening";
  const page = await open(browser, path.join(work, "flat.html"), problems);
  await commonChecks(page, what, problems);
  const report = JSON.parse(fs.readFileSync(path.join(work, "flat.json"), "utf8"));
  await numbersEqualReport(page, what, report);
  // The page finds the seams where the texture coordinates jump; the report lists the
  // edges cut. Each seam edge is drawn from both of its sides.
  const seams = await page.evaluate(() => surfmapView.data.arrays["surface.seams"].length);
  check(`${what}: both sides of each of the report's seam edges are drawn`, seams === 2 * report.seams.edges.length,
    `${seams} half-edges, ${report.seams.edges.length} seam edges`);
  await dragChanges(page, what, "surface");
  const before = (await snapshot(page)).hash;
  await page.select("#colour", "angle");
  const legend = await page.evaluate(() => document.querySelector(".legend").textContent);
  check(`${what}: colouring by the angle distortion changes the pixels and shows a legend`,
    before !== (await snapshot(page)).hash && /angle/.test(legend) && /(clips|does not clip)/.test(legend), legend);
  if (shots) await page.screenshot({ path: path.join(shots, "viewer_flattening.png") });
  await page.close();
}

// A vertex of A picked with the mouse: the page must report it and draw its image on B
// where the correspondence puts it, and (for the generated match) where the closed-form
// map puts it.
async function matchPage(browser, work, file, folder, bFile, closedForm, shots) {
  const problems = [], what = `match ${path.basename(file)}`;
  const page = await open(browser, path.join(work, file), problems);
  await commonChecks(page, what, problems);
  const info = JSON.parse(fs.readFileSync(path.join(folder, "match.json"), "utf8"));
  if (info.vertices_a !== undefined) await numbersEqualReport(page, what, info);
  const corr = readNpy(path.join(folder, "correspondence.npy"));
  const B = readObj(bFile);
  const unmatched = Array.from({ length: corr.shape[0] }, (_, v) => corr.data[4 * v] < 0).filter(Boolean).length;
  const counts = await page.evaluate(() => surfmapView.data.counts);
  check(`${what}: unmatched vertices as in correspondence.npy`, counts.unmatched === unmatched, `${counts.unmatched} vs ${unmatched}`);
  // The matched vertex of A drawn nearest the centre of A's panel.
  const target = await page.evaluate(() => {
    const p = surfmapView.panels.a, r = document.getElementById("gl").getBoundingClientRect();
    const cx = r.left + p.px.x + p.px.w / 2, cy = r.top + p.px.h / 2;
    const t = surfmapView.data.arrays["corr.triangle"].length;
    let best = null;
    for (let v = 0; v < t; v++) {
      if (!surfmapView.imageOnB(v)) continue;
      const q = surfmapView.project("a", surfmapView.vertexA(v));
      const d = Math.hypot(q.x - cx, q.y - cy);
      if (!best || d < best.d) best = { v, x: q.x, y: q.y, d };
    }
    return best;
  });
  await page.mouse.click(target.x, target.y);
  const picked = await page.evaluate(() => surfmapView.picked);
  const v = target.v, row = corr.data.subarray(4 * v, 4 * v + 4), tri = B.f[row[0]];
  const expected = [0, 1, 2].map((c) => row[1] * B.v[tri[0]][c] + row[2] * B.v[tri[1]][c] + row[3] * B.v[tri[2]][c]);
  const scale = Math.max(...B.v.map((p) => Math.hypot(...p)));
  check(`${what}: clicking vertex ${v} of A picks it`, picked && picked.vertex === v, picked && `picked ${picked.vertex}`);
  check(`${what}: its image on B is the correspondence's point`, picked && picked.b && dist(picked.b, expected) < 1e-5 * scale,
    picked && picked.b && `off by ${dist(picked.b, expected).toExponential(2)}`);
  if (closedForm) {
    const a = readObj(path.join(work, "in", "a.obj")).v[v];
    const f = closedForm.map([a[0], a[1]]);
    const exact = [f[0], f[1], closedForm.height(f[0], f[1])];
    check(`${what}: and the closed-form map's point (within B's piecewise-linear error)`, picked && picked.b && dist(picked.b, exact) < 0.01,
      picked && picked.b && `off by ${dist(picked.b, exact).toExponential(2)}`);
  }
  const spot = await page.evaluate((x) => surfmapView.project("b", x), expected);
  const px = await page.evaluate((s) => surfmapView.pixelAt(s.x, s.y), spot);
  check(`${what}: the picked point is highlighted on B`, px[0] > 200 && px[1] > 150 && px[2] < 90, `pixel ${px}`);
  if (shots) await page.screenshot({ path: path.join(shots, "viewer_match.png") });
  await sliderChanges(page, what, "morph", 1);
  const end = await page.evaluate((v) => surfmapView.vertexA(v), v);
  check(`${what}: at morph 1 the vertex is at its image on B`, dist(end, expected) < 1e-5 * scale, `off by ${dist(end, expected).toExponential(2)}`);
  await dragChanges(page, what, "b");
  await page.close();
}

async function rigPage(browser, work, shots) {
  const problems = [], what = "rig";
  const page = await open(browser, path.join(work, "rig.html"), problems);
  await commonChecks(page, what, problems);
  const labels = await page.evaluate(() => Array.from(document.querySelectorAll("#side label")).map((l) => l.textContent));
  check(`${what}: one slider per named target`, labels.some((l) => l.startsWith("wide ")) && labels.some((l) => l.startsWith("wider ")), labels.join(", "));
  await sliderChanges(page, what, "target-1", 1);
  const before = (await snapshot(page)).hash;
  await page.click("#play");
  await new Promise((r) => setTimeout(r, 600));
  await page.click("#play");
  check(`${what}: playing the animation changes the pixels`, before !== (await snapshot(page)).hash);
  if (shots) {
    await page.$eval("#target-1", (e) => { e.value = "0.8"; e.dispatchEvent(new Event("input")); });
    await page.screenshot({ path: path.join(shots, "viewer_rig.png") });
  }
  await page.close();
}

async function tablePage(browser, work, shots) {
  const problems = [], what = "batch table";
  const page = await open(browser, path.join(work, "batch.html"), problems);
  await commonChecks(page, what, problems);
  const rows = await page.$$eval("#summary tbody tr", (t) => t.length);
  const summary = fs.readFileSync(path.join(work, "batch", "summary.csv"), "utf8").trim().split("\n").length - 1;
  check(`${what}: one row per mesh of summary.csv`, rows === summary, `${rows} vs ${summary}`);
  if (shots) await page.screenshot({ path: path.join(shots, "viewer_table.png") });
  const link = await page.$eval("#summary a", (a) => a.getAttribute("href"));
  await page.close();
  const itemProblems = [];
  const item = await open(browser, path.join(work, link), itemProblems);
  await commonChecks(item, `${what} item ${link}`, itemProblems);
  await item.close();
}

// ---------------------------------------------------------------- bench
async function bench(browser, files) {
  for (const file of files) {
    const times = [], decode = [], redraw = [], slide = [];
    for (let i = 0; i < 5; i++) {
      const problems = [];
      const page = await open(browser, file, problems);
      const t = await page.evaluate(() => ({ first: surfmapView.firstFrameMs, decode: surfmapView.decodeMs, renderer: surfmapView.renderer }));
      if (i === 0) console.log(`${path.basename(file)}: WebGL renderer ${t.renderer}`);
      times.push(t.first); decode.push(t.decode);
      // A redraw waited for (pixels read back), as after a drag or a slider.
      redraw.push(await page.evaluate(() => {
        const r = document.getElementById("gl").getBoundingClientRect();
        const [x, y] = [r.left + r.width / 2, r.top + r.height / 2];
        const t0 = performance.now();
        for (let i = 0; i < 5; i++) surfmapView.pixelAt(x, y);
        return (performance.now() - t0) / 5;
      }));
      // The morph slider moved (vertices, normals and buffers refilled) and drawn.
      slide.push(await page.evaluate(() => {
        const s = document.getElementById("morph");
        if (!s) return NaN;
        const r = document.getElementById("gl").getBoundingClientRect();
        const [x, y] = [r.left + r.width / 2, r.top + r.height / 2];
        const t0 = performance.now();
        for (let i = 1; i <= 5; i++) { s.value = String(i / 5); s.dispatchEvent(new Event("input")); surfmapView.pixelAt(x, y); }
        return (performance.now() - t0) / 5;
      }));
      if (problems.length) console.log(`${file}: ${problems.join(" | ")}`);
      await page.close();
    }
    const median = (a) => a.slice().sort((x, y) => x - y)[Math.floor(a.length / 2)];
    console.log(`${path.basename(file)}\t${(fs.statSync(file).size / 1e6).toFixed(2)} MB\tfirst frame ${median(times).toFixed(0)} ms (median of 5, from navigation start)\tdecode + build ${median(decode).toFixed(0)} ms\tredraw ${median(redraw).toFixed(0)} ms${isNaN(slide[0]) ? "" : `\tmorph slider step ${median(slide).toFixed(0)} ms`}`);
  }
}

const { browser, profile } = await launch();
try {
  if (args[0] === "--bench") await bench(browser, args.slice(1));
  else {
    const work = args[0];
    const s = args.indexOf("--screenshots");
    const shots = s >= 0 ? args[s + 1] : null;
    if (shots) { fs.mkdirSync(shots, { recursive: true }); hash = "#antialias"; }
    // The generated match's closed form (surfmap::apps::inputs): A's (x, y) goes to f(x, y)
    // on B, a graph z = h(x, y).
    const closedForm = {
      map: ([x, y]) => [0.9 * x + 0.08 * y * y, 0.95 * y + 0.05 * x],
      height: (x, y) => 0.45 * Math.exp(-(x * x + 2 * y * y)) + 0.1 * x,
    };
    await flatteningPage(browser, work, shots);
    await matchPage(browser, work, "match_generated.html", path.join(work, "in", "match_ab"), path.join(work, "in", "b.obj"), closedForm, null);
    await matchPage(browser, work, "match_cli.html", path.join(work, "match_cli"), path.join(work, "in", "b.obj"), null, shots);
    await rigPage(browser, work, shots);
    await tablePage(browser, work, shots);
    console.log(`view_test: ${passed} passed, ${failed} failed`);
  }
} finally {
  await browser.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
process.exit(failed ? 1 : 0);
