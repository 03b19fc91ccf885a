// Opens a fullarm report.html in headless Chromium and checks that it works from disk alone.
//
// Usage: node tests/reports/check_report.mjs <report.html> <screenshot.png> [--min-charts N]
//          [--min-replays N] [--summary summary.json [--expect-penetration]]
//
// Fails (exit status 1) on any console error or page error, on any request that is not a
// file: or data: URL, if a [data-chart] element does not reach data-rendered="true" within
// 30 s, or if a chart's SVG holds no plotted content; exit status 2 on bad usage. Saves a
// full-page screenshot either way. Environment: FULLARM_CHROMIUM overrides /usr/bin/chromium.
//
// 3D replays ([data-replay3d], drawn with WebGL: headless Chromium has no GPU here and draws
// with SwiftShader): each must render, its canvas must not be blank (a pixel count), and
// moving its time slider from the first to the last frame must change the picture (two
// screenshots of the replay, saved beside <screenshot.png>, must differ). With --summary, the
// report's summary.json names, per link, the time of its first penetration
// (results.replay3d.first_penetration_s): at the frame holding that time the page's own state
// must show the link penetrating and drawn in the penetration colour, and one frame earlier
// not; --expect-penetration fails when no link penetrates at all.
//
// Chromium is driven through the DevTools protocol over a pipe (--remote-debugging-pipe: JSON
// messages separated by NUL bytes on file descriptors 3 and 4), with Node's standard library
// alone: no npm package, and any Node.js from 18 on (Debian 12's own).
import { spawn } from "node:child_process";
import { mkdtemp, rm, mkdir, writeFile, readFile } from "node:fs/promises";
import { existsSync } from "node:fs";
import { tmpdir } from "node:os";
import path from "node:path";
import { pathToFileURL } from "node:url";

const kRenderTimeoutMs = 30_000;
const kProtocolTimeoutMs = 60_000;
const kViewport = { width: 1280, height: 900 };

function usage(message) {
  console.error(`check_report: ${message}`);
  console.error("usage: node check_report.mjs <report.html> <screenshot.png> [--min-charts N]");
  process.exit(2);
}

const args = process.argv.slice(2);
let minCharts = 1;
let minReplays = 0;
let summaryPath = null;
let expectPenetration = false;
const positional = [];
for (let i = 0; i < args.length; ++i) {
  if (args[i] === "--min-charts") {
    minCharts = Number.parseInt(args[++i], 10);
    if (!Number.isInteger(minCharts) || minCharts < 0) usage("--min-charts needs a count");
  } else if (args[i] === "--min-replays") {
    minReplays = Number.parseInt(args[++i], 10);
    if (!Number.isInteger(minReplays) || minReplays < 0) usage("--min-replays needs a count");
  } else if (args[i] === "--summary") {
    summaryPath = args[++i];
    if (!summaryPath) usage("--summary needs a path");
  } else if (args[i] === "--expect-penetration") {
    expectPenetration = true;
  } else {
    positional.push(args[i]);
  }
}
if (positional.length !== 2) usage("expected a report path and a screenshot path");
const reportPath = path.resolve(positional[0]);
const screenshotPath = path.resolve(positional[1]);
if (!existsSync(reportPath)) usage(`no such file: ${reportPath}`);
const executablePath = process.env.FULLARM_CHROMIUM || "/usr/bin/chromium";
if (!existsSync(executablePath)) usage(`no Chromium at ${executablePath} (set FULLARM_CHROMIUM)`);

// A DevTools-protocol connection over Chromium's pipe: send() returns the command's result,
// on() subscribes to events of a session.
class Browser {
  constructor(child) {
    this.child = child;
    this.nextId = 1;
    this.pending = new Map();
    this.listeners = [];
    this.buffer = Buffer.alloc(0);
    this.closed = false;
    child.stdio[4].on("data", (chunk) => this.receive(chunk));
    child.on("exit", (code, signal) => {
      this.closed = true;
      for (const { reject } of this.pending.values()) {
        reject(new Error(`Chromium exited (code ${code}, signal ${signal})`));
      }
      this.pending.clear();
    });
  }

  receive(chunk) {
    this.buffer = Buffer.concat([this.buffer, chunk]);
    let end;
    while ((end = this.buffer.indexOf(0)) !== -1) {
      const message = JSON.parse(this.buffer.subarray(0, end).toString("utf8"));
      this.buffer = this.buffer.subarray(end + 1);
      if (message.id !== undefined) {
        const waiter = this.pending.get(message.id);
        this.pending.delete(message.id);
        if (!waiter) continue;
        clearTimeout(waiter.timer);
        if (message.error) waiter.reject(new Error(`${waiter.method}: ${message.error.message}`));
        else waiter.resolve(message.result);
      } else {
        for (const listener of this.listeners) {
          if (listener.method === message.method && listener.sessionId === message.sessionId) {
            listener.handler(message.params);
          }
        }
      }
    }
  }

  send(method, params = {}, sessionId = undefined) {
    if (this.closed) return Promise.reject(new Error(`${method}: Chromium has exited`));
    const id = this.nextId++;
    const message = { id, method, params };
    if (sessionId) message.sessionId = sessionId;
    return new Promise((resolve, reject) => {
      const timer = setTimeout(() => {
        this.pending.delete(id);
        reject(new Error(`${method}: no answer within ${kProtocolTimeoutMs / 1000} s`));
      }, kProtocolTimeoutMs);
      this.pending.set(id, { resolve, reject, method, timer });
      this.child.stdio[3].write(JSON.stringify(message) + "\0");
    });
  }

  on(method, sessionId, handler) {
    this.listeners.push({ method, sessionId, handler });
  }

  once(method, sessionId) {
    return new Promise((resolve) => {
      const listener = { method, sessionId, handler: (params) => {
        this.listeners.splice(this.listeners.indexOf(listener), 1);
        resolve(params);
      } };
      this.listeners.push(listener);
    });
  }
}

// Evaluates `expression` in the page and returns its value (awaiting a promise).
async function evaluate(browser, sessionId, expression) {
  const { result, exceptionDetails } = await browser.send(
    "Runtime.evaluate", { expression, awaitPromise: true, returnByValue: true }, sessionId);
  if (exceptionDetails) {
    throw new Error(`evaluation failed: ${exceptionDetails.exception?.description ?? exceptionDetails.text}`);
  }
  return result.value;
}

// Pixels of a replay's canvas that are not background white, and a sample of distinct colours.
function canvasPixelsExpression(id) {
  return `(() => {
    const canvas = document.querySelector('[data-replay3d="${id}"] canvas');
    const copy = document.createElement("canvas");
    copy.width = canvas.width;
    copy.height = canvas.height;
    const context = copy.getContext("2d");
    context.drawImage(canvas, 0, 0);
    const data = context.getImageData(0, 0, copy.width, copy.height).data;
    let drawn = 0;
    let hash = 0;
    const colours = new Set();
    for (let i = 0; i < data.length; i += 4) {
      if (data[i] < 245 || data[i + 1] < 245 || data[i + 2] < 245) ++drawn;
      if (i % 256 === 0) colours.add((data[i] << 16) | (data[i + 1] << 8) | data[i + 2]);
      hash = (hash * 31 + data[i] + 7 * data[i + 1] + 13 * data[i + 2]) >>> 0;
    }
    return { drawn, total: data.length / 4, colours: colours.size, hash };
  })()`;
}

// Moves replay `id`'s slider to `frame` the way a user does (value, then an input event).
function moveSliderExpression(id, frame) {
  return `(() => {
    const slider = document.querySelector('[data-replay3d="${id}"] input[type=range]');
    slider.value = String(${frame});
    slider.dispatchEvent(new Event("input", { bubbles: true }));
    return window.fullarmReplays["${id}"].state().frame;
  })()`;
}

async function screenshotOf(browser, sessionId, id, file) {
  const rect = await evaluate(browser, sessionId, `(() => {
      const element = document.querySelector('[data-replay3d="${id}"]');
      element.scrollIntoView();
      const r = element.getBoundingClientRect();
      return { x: r.left + window.scrollX, y: r.top + window.scrollY, width: r.width, height: r.height };
    })()`);
  const { data } = await browser.send("Page.captureScreenshot", {
    format: "png", captureBeyondViewport: true, clip: { ...rect, scale: 1 } }, sessionId);
  const bytes = Buffer.from(data, "base64");
  await mkdir(path.dirname(file), { recursive: true });
  await writeFile(file, bytes);
  return bytes;
}

async function checkReplays(browser, sessionId) {
  const ids = await evaluate(browser, sessionId,
                             `[...document.querySelectorAll("[data-replay3d]")].map((e) => e.dataset.replay3d)`);
  if (ids.length < minReplays) problems.push(`found ${ids.length} 3D replays, expected at least ${minReplays}`);
  if (ids.length === 0) {
    if (summaryPath) problems.push("--summary given but the report holds no 3D replay");
    return;
  }
  await evaluate(browser, sessionId, `new Promise((resolve) => {
      const start = performance.now();
      const poll = () => {
        const all = [...document.querySelectorAll("[data-replay3d]")];
        if (all.every((element) => element.hasAttribute("data-rendered"))) return resolve(true);
        if (performance.now() - start > ${kRenderTimeoutMs}) return resolve(false);
        setTimeout(poll, 50);
      };
      poll();
    })`);
  let firstPenetration = {};
  if (summaryPath) {
    const summary = JSON.parse(await readFile(summaryPath, "utf8"));
    firstPenetration = summary?.results?.replay3d?.first_penetration_s ?? {};
  }
  const base = screenshotPath.replace(/\.png$/, "");
  for (const id of ids) {
    const rendered = await evaluate(browser, sessionId,
                                    `document.querySelector('[data-replay3d="${id}"]').getAttribute("data-rendered")`);
    if (rendered !== "true") {
      problems.push(`replay ${id}: data-rendered=${rendered}`);
      continue;
    }
    const state = await evaluate(browser, sessionId, `window.fullarmReplays["${id}"].state()`);
    await evaluate(browser, sessionId, moveSliderExpression(id, 0));
    const first = await evaluate(browser, sessionId, canvasPixelsExpression(id));
    if (first.drawn < 0.01 * first.total || first.colours < 3) {
      problems.push(`replay ${id}: the canvas is blank (${first.drawn} of ${first.total} pixels drawn, ` +
                    `${first.colours} colours)`);
    }
    const shotA = await screenshotOf(browser, sessionId, id, `${base}-${id}-first.png`);
    const last = await evaluate(browser, sessionId, moveSliderExpression(id, state.frameCount - 1));
    if (last !== state.frameCount - 1) problems.push(`replay ${id}: the slider moved to frame ${last}, not the last`);
    const moved = await evaluate(browser, sessionId, canvasPixelsExpression(id));
    const shotB = await screenshotOf(browser, sessionId, id, `${base}-${id}-last.png`);
    if (shotA.equals(shotB)) problems.push(`replay ${id}: moving the slider did not change the screenshot`);
    if (moved.hash === first.hash) problems.push(`replay ${id}: moving the slider did not change the canvas`);
    console.log(`check_report: replay ${id}: ${state.frameCount} frames, ${first.drawn} of ${first.total} ` +
                `pixels drawn; screenshots ${base}-${id}-first.png, ${base}-${id}-last.png`);

    const penetrating = Object.entries(firstPenetration).filter(([, t]) => t !== null);
    if (summaryPath && expectPenetration && penetrating.length === 0) {
      problems.push(`replay ${id}: no link penetrates in ${summaryPath} (results.replay3d.first_penetration_s)`);
    }
    for (const [name, t] of penetrating) {
      const link = state.links.indexOf(name);
      if (link < 0) {
        problems.push(`replay ${id}: link ${name} of the summary is not in the replay`);
        continue;
      }
      const frame = state.times.findIndex((time) => time >= t - 1e-9);
      if (frame < 0) {
        problems.push(`replay ${id}: no frame at or after ${name}'s first penetration at ${t} s`);
        continue;
      }
      await evaluate(browser, sessionId, moveSliderExpression(id, frame));
      const at = await evaluate(browser, sessionId, `window.fullarmReplays["${id}"].state()`);
      if (!at.penetrating[link] || at.linkColors[link] !== at.penetratingColor) {
        problems.push(`replay ${id}: at ${at.t_s} s (frame ${frame}) ${name} penetrates from ${t} s but is drawn ` +
                      `${at.linkColors[link]} (penetrating flag ${at.penetrating[link]}, expected ` +
                      `${at.penetratingColor})`);
      }
      await screenshotOf(browser, sessionId, id, `${base}-${id}-${name}-penetrating.png`);
      if (frame > 0) {
        await evaluate(browser, sessionId, moveSliderExpression(id, frame - 1));
        const before = await evaluate(browser, sessionId, `window.fullarmReplays["${id}"].state()`);
        if (before.penetrating[link] || before.linkColors[link] === before.penetratingColor) {
          problems.push(`replay ${id}: at ${before.t_s} s, before its first penetration at ${t} s, ${name} is ` +
                        `drawn in the penetration colour`);
        }
      }
      console.log(`check_report: replay ${id}: ${name} penetrates from ${t} s, drawn ${at.linkColors[link]} ` +
                  `in frame ${frame} (${at.t_s} s)`);
    }
  }
}

const problems = [];
const userDataDir = await mkdtemp(path.join(tmpdir(), "fullarm-check-report-"));
let child;
let chromiumLog = "";
try {
  child = spawn(executablePath, [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    // WebGL without a GPU: SwiftShader, the software renderer Chromium ships.
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--hide-scrollbars",
    "--mute-audio",
    `--user-data-dir=${userDataDir}`,
    `--window-size=${kViewport.width},${kViewport.height}`,
    "--remote-debugging-pipe",
    "about:blank",
  ], { stdio: ["ignore", "ignore", "pipe", "pipe", "pipe"] });
  child.stderr.on("data", (chunk) => { chromiumLog = (chromiumLog + chunk.toString()).slice(-4000); });
  const spawned = new Promise((resolve, reject) => {
    child.once("spawn", resolve);
    child.once("error", reject);
  });
  await spawned;
  const browser = new Browser(child);

  // The page target Chromium opened, in a flat session.
  const { targetInfos } = await browser.send("Target.getTargets");
  let page = targetInfos.find((target) => target.type === "page");
  if (!page) {
    const { targetId } = await browser.send("Target.createTarget", { url: "about:blank" });
    page = { targetId };
  }
  const { sessionId } = await browser.send("Target.attachToTarget", { targetId: page.targetId, flatten: true });

  browser.on("Runtime.consoleAPICalled", sessionId, (event) => {
    if (event.type === "error" || event.type === "assert") {
      const text = event.args.map((arg) => arg.value ?? arg.description ?? "").join(" ");
      problems.push(`console error: ${text}`);
    }
  });
  browser.on("Runtime.exceptionThrown", sessionId, (event) => {
    const details = event.exceptionDetails;
    problems.push(`page error: ${details.exception?.description ?? details.text}`);
  });
  browser.on("Log.entryAdded", sessionId, (event) => {
    if (event.entry.level === "error") problems.push(`console error: ${event.entry.text}`);
  });
  // Anything but file: and data: is a network request: record it and never let it out.
  browser.on("Fetch.requestPaused", sessionId, (event) => {
    const url = event.request.url;
    if (url.startsWith("file:") || url.startsWith("data:")) {
      browser.send("Fetch.continueRequest", { requestId: event.requestId }, sessionId).catch(() => {});
    } else {
      problems.push(`network request: ${url}`);
      browser.send("Fetch.failRequest", { requestId: event.requestId, errorReason: "BlockedByClient" }, sessionId)
        .catch(() => {});
    }
  });
  browser.on("Network.requestWillBeSent", sessionId, (event) => {
    const url = event.request.url;
    if (!url.startsWith("file:") && !url.startsWith("data:")) problems.push(`request: ${url}`);
  });

  await browser.send("Runtime.enable", {}, sessionId);
  await browser.send("Log.enable", {}, sessionId);
  await browser.send("Page.enable", {}, sessionId);
  await browser.send("Network.enable", {}, sessionId);
  await browser.send("Network.emulateNetworkConditions",
                     { offline: true, latency: 0, downloadThroughput: -1, uploadThroughput: -1 }, sessionId);
  await browser.send("Fetch.enable", { patterns: [{ urlPattern: "*" }] }, sessionId);
  await browser.send("Emulation.setDeviceMetricsOverride",
                     { width: kViewport.width, height: kViewport.height, deviceScaleFactor: 1, mobile: false },
                     sessionId);

  const loaded = browser.once("Page.loadEventFired", sessionId);
  const navigation = await browser.send("Page.navigate", { url: pathToFileURL(reportPath).href }, sessionId);
  if (navigation.errorText) throw new Error(`navigation failed: ${navigation.errorText}`);
  await loaded;

  const chartCount = await evaluate(browser, sessionId, `document.querySelectorAll("[data-chart]").length`);
  if (chartCount < minCharts) {
    problems.push(`found ${chartCount} [data-chart] elements, expected at least ${minCharts}`);
  }
  // Wait until every chart has settled: data-rendered is "true", or "error" on failure.
  const settled = await evaluate(browser, sessionId, `new Promise((resolve) => {
      const start = performance.now();
      const poll = () => {
        const all = [...document.querySelectorAll("[data-chart]")];
        if (all.every((element) => element.hasAttribute("data-rendered"))) return resolve(true);
        if (performance.now() - start > ${kRenderTimeoutMs}) return resolve(false);
        setTimeout(poll, 50);
      };
      poll();
    })`);
  const notRendered = await evaluate(browser, sessionId, `[...document.querySelectorAll("[data-chart]")]
      .filter((element) => element.getAttribute("data-rendered") !== "true")
      .map((element) => element.dataset.chart + " (data-rendered=" + element.getAttribute("data-rendered") + ")")`);
  if (notRendered.length > 0) {
    problems.push(`charts not rendered${settled ? "" : ` within ${kRenderTimeoutMs / 1000} s`}: ` +
                  notRendered.join(", "));
  }

  // Each chart must have drawn something: a trace path with geometry or a heat-map image.
  const charts = await evaluate(browser, sessionId, `[...document.querySelectorAll("[data-chart]")].map((element) => {
      const svg = element.querySelector("svg.main-svg");
      const shapes = [...element.querySelectorAll(
        "svg.main-svg .trace path, svg.main-svg .trace image, svg.main-svg .hm image")];
      const drawn = shapes.filter((shape) => {
        if (shape.tagName.toLowerCase() === "image") {
          return (shape.getAttribute("href") || shape.getAttribute("xlink:href") || "").length > 0;
        }
        const d = shape.getAttribute("d") || "";
        return d.length > 0 && d !== "M0,0Z";
      }).length;
      return { id: element.dataset.chart, hasSvg: Boolean(svg), drawn };
    })`);
  for (const chart of charts) {
    if (!chart.hasSvg) problems.push(`chart ${chart.id}: no SVG`);
    else if (chart.drawn === 0) problems.push(`chart ${chart.id}: SVG has no plotted content`);
  }

  await checkReplays(browser, sessionId);

  // The page must open with its verdict.
  const headline = await evaluate(browser, sessionId,
                                  `(document.querySelector("h1")?.textContent ?? "").trim()`);
  if (!headline) problems.push("no <h1> title");
  const badges = await evaluate(browser, sessionId, `document.querySelectorAll(".verdict .badge").length`);
  if (badges !== 1) problems.push("no verdict badge");

  // Full-page screenshot: the viewport grown to the page's height.
  const metrics = await browser.send("Page.getLayoutMetrics", {}, sessionId);
  const fullHeight = Math.ceil((metrics.cssContentSize ?? metrics.contentSize).height);
  await browser.send("Emulation.setDeviceMetricsOverride",
                     { width: kViewport.width, height: Math.max(kViewport.height, fullHeight),
                       deviceScaleFactor: 1, mobile: false }, sessionId);
  const { data } = await browser.send("Page.captureScreenshot", { format: "png", captureBeyondViewport: true },
                                      sessionId);
  await mkdir(path.dirname(screenshotPath), { recursive: true });
  await writeFile(screenshotPath, Buffer.from(data, "base64"));
  const drawn = charts.map((chart) => `${chart.id}: ${chart.drawn}`).join(", ");
  console.log(`check_report: ${reportPath}: ${charts.length} charts (drawn shapes ${drawn})`);
  console.log(`check_report: screenshot ${screenshotPath}`);
  await browser.send("Browser.close").catch(() => {});
} catch (error) {
  problems.push(`unexpected failure: ${error.stack || error}`);
  if (chromiumLog) console.error(`check_report: the end of Chromium's log:\n${chromiumLog}`);
} finally {
  if (child && child.exitCode === null && child.signalCode === null) {
    const exited = new Promise((resolve) => child.once("exit", resolve));
    const timer = setTimeout(() => child.kill("SIGKILL"), 3_000);
    await exited;
    clearTimeout(timer);
  }
  await rm(userDataDir, { recursive: true, force: true });
}

if (problems.length > 0) {
  for (const problem of problems) console.error(`check_report: FAIL: ${problem}`);
  process.exit(1);
}
console.log("check_report: OK");
