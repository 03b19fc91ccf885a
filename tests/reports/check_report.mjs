// Opens a fullarm report.html in headless Chromium and checks that it works from disk alone.
//
// Usage: node tests/reports/check_report.mjs <report.html> <screenshot.png> [--min-charts N]
//
// Fails (exit status 1) on any console error or page error, on any request that is not a
// file: or data: URL, if a [data-chart] element does not reach data-rendered="true" within
// 30 s, or if a chart's SVG holds no plotted content; exit status 2 on bad usage. Saves a
// full-page screenshot either way. Environment: FULLARM_CHROMIUM overrides /usr/bin/chromium.
import { chromium } from "playwright-core";
import { mkdtemp, rm, mkdir } from "node:fs/promises";
import { existsSync } from "node:fs";
import { tmpdir } from "node:os";
import path from "node:path";
import { pathToFileURL } from "node:url";

const kRenderTimeoutMs = 30_000;
const kViewport = { width: 1280, height: 900 };

function usage(message) {
  console.error(`check_report: ${message}`);
  console.error("usage: node check_report.mjs <report.html> <screenshot.png> [--min-charts N]");
  process.exit(2);
}

const args = process.argv.slice(2);
let minCharts = 1;
const positional = [];
for (let i = 0; i < args.length; ++i) {
  if (args[i] === "--min-charts") {
    minCharts = Number.parseInt(args[++i], 10);
    if (!Number.isInteger(minCharts) || minCharts < 0) usage("--min-charts needs a count");
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

const problems = [];
const userDataDir = await mkdtemp(path.join(tmpdir(), "fullarm-check-report-"));
let context;
try {
  context = await chromium.launchPersistentContext(userDataDir, {
    executablePath,
    headless: true,
    viewport: kViewport,
    offline: true,
    args: [
      "--headless",
      "--no-sandbox",
      "--disable-gpu",
      "--disable-quic",
      "--no-first-run",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
    ],
  });
  const page = context.pages()[0] ?? (await context.newPage());

  page.on("console", (message) => {
    if (message.type() === "error") problems.push(`console error: ${message.text()}`);
  });
  page.on("pageerror", (error) => problems.push(`page error: ${error.message}`));
  // Anything but file: and data: is a network request: record it and never let it out.
  await context.route("**/*", (route) => {
    const url = route.request().url();
    if (url.startsWith("file:") || url.startsWith("data:")) return route.continue();
    problems.push(`network request: ${url}`);
    return route.abort("blockedbyclient");
  });
  page.on("request", (request) => {
    const url = request.url();
    if (!url.startsWith("file:") && !url.startsWith("data:")) {
      problems.push(`request: ${url}`);
    }
  });

  await page.goto(pathToFileURL(reportPath).href, { waitUntil: "load" });

  const chartCount = await page.locator("[data-chart]").count();
  if (chartCount < minCharts) {
    problems.push(`found ${chartCount} [data-chart] elements, expected at least ${minCharts}`);
  }
  // Wait until every chart has settled: data-rendered is "true", or "error" on failure.
  let settled = true;
  try {
    await page.waitForFunction(
      () => [...document.querySelectorAll("[data-chart]")].every(
        (element) => element.hasAttribute("data-rendered")),
      null, { timeout: kRenderTimeoutMs });
  } catch {
    settled = false;
  }
  const notRendered = await page.$$eval("[data-chart]", (elements) => elements
    .filter((element) => element.getAttribute("data-rendered") !== "true")
    .map((element) => `${element.dataset.chart} (data-rendered=${element.getAttribute("data-rendered")})`));
  if (notRendered.length > 0) {
    problems.push(`charts not rendered${settled ? "" : ` within ${kRenderTimeoutMs / 1000} s`}: ` +
                  notRendered.join(", "));
  }

  // Each chart must have drawn something: a trace path with geometry or a heat-map image.
  const charts = await page.$$eval("[data-chart]", (elements) => elements.map((element) => {
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
  }));
  for (const chart of charts) {
    if (!chart.hasSvg) problems.push(`chart ${chart.id}: no SVG`);
    else if (chart.drawn === 0) problems.push(`chart ${chart.id}: SVG has no plotted content`);
  }

  // The page must open with its verdict.
  const headline = await page.$eval("h1", (element) => element.textContent.trim()).catch(() => "");
  if (!headline) problems.push("no <h1> title");
  if ((await page.locator(".verdict .badge").count()) !== 1) problems.push("no verdict badge");

  await mkdir(path.dirname(screenshotPath), { recursive: true });
  await page.screenshot({ path: screenshotPath, fullPage: true });
  const drawn = charts.map((chart) => `${chart.id}: ${chart.drawn}`).join(", ");
  console.log(`check_report: ${reportPath}: ${charts.length} charts (drawn shapes ${drawn})`);
  console.log(`check_report: screenshot ${screenshotPath}`);
} catch (error) {
  problems.push(`unexpected failure: ${error.stack || error}`);
} finally {
  if (context) await context.close();
  await rm(userDataDir, { recursive: true, force: true });
}

if (problems.length > 0) {
  for (const problem of problems) console.error(`check_report: FAIL: ${problem}`);
  process.exit(1);
}
console.log("check_report: OK");
