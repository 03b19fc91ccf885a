// Bundles the partial plotly.js of fullarm reports (plotly_partial.js) into one minified script
// with esbuild; the build runs it (reports/CMakeLists.txt).
//
// Usage: node bundle_plotly.mjs <entry.js> <node_modules dir> <output.js>
//
// Fails (exit status 1) when a package is missing or the bundle holds a <script> tag (it is
// inlined into a <script> element of every report.html).
import { createRequire } from "node:module";
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";

if (process.argv.length !== 5) {
  console.error("usage: node bundle_plotly.mjs <entry.js> <node_modules dir> <output.js>");
  process.exit(2);
}
const [entry, nodeModules, output] = process.argv.slice(2).map((p) => path.resolve(p));
const require = createRequire(path.join(nodeModules, "fullarm-bundle.js"));
let esbuild;
let plotlyPackage;
try {
  esbuild = require("esbuild");
  plotlyPackage = JSON.parse(readFileSync(path.join(nodeModules, "plotly.js", "package.json"), "utf8"));
} catch (error) {
  console.error(`bundle_plotly: ${error.message}: run npm ci in the repository (scripts/setup-deps does it)`);
  process.exit(1);
}

const result = esbuild.buildSync({
  entryPoints: [entry],
  nodePaths: [nodeModules],
  bundle: true,
  minify: true,
  format: "iife",
  globalName: "Plotly",
  target: "es2017",
  legalComments: "none",
  // A map-trace branch of plotly.js imports a style sheet; no trace here takes it.
  loader: { ".css": "empty" },
  // Dependencies written for browserify read `global`; in a page it is `window`.
  define: { global: "window" },
  banner: {
    js: `/*! plotly.js v${plotlyPackage.version} (core, scatter, heatmap) | Copyright Plotly, Inc. | MIT licence */`,
  },
  write: false,
  logLevel: "warning",
});
const text = result.outputFiles[0].text;
const lower = text.toLowerCase();
if (lower.includes("</script") || lower.includes("<script")) {
  console.error("bundle_plotly: the bundle contains a <script> tag and cannot be inlined");
  process.exit(1);
}
writeFileSync(output, text);
console.log(`bundle_plotly: ${output} (${text.length} bytes, plotly.js ${plotlyPackage.version})`);
