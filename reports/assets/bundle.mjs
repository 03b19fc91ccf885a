// Bundles one front-end library of fullarm reports with esbuild into a minified script that
// report.html inlines; the build runs it (reports/CMakeLists.txt). Two bundles:
//   plotly    the partial plotly.js (plotly_partial.js: core, scatter, heatmap), in every report
//   replay3d  the 3D replay (replay3d.js with the parts of three.js it imports), in the reports
//             that hold a replay
//
// Usage: node bundle.mjs <plotly|replay3d> <entry.js> <node_modules dir> <output.js>
//
// Fails (exit status 1) when a package is missing or the bundle holds a <script> tag (it is
// inlined into a <script> element).
import { createRequire } from "node:module";
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";

// Per bundle: the npm package whose version it names, esbuild's options beyond the common ones,
// and the licence banner.
const bundles = {
  plotly: {
    packageName: "plotly.js",
    options: {
      globalName: "Plotly",
      target: "es2017",
      // A map-trace branch of plotly.js imports a style sheet; no trace here takes it.
      loader: { ".css": "empty" },
      // Dependencies written for browserify read `global`; in a page it is `window`.
      define: { global: "window" },
    },
    banner: (version) => `/*! plotly.js v${version} (core, scatter, heatmap) | Copyright Plotly, Inc. | MIT licence */`,
  },
  replay3d: {
    packageName: "three",
    options: { target: "es2018" },
    banner: (version) =>
      `/*! three.js r${version.split(".")[1]} | Copyright 2010-2025 three.js authors | MIT licence */`,
  },
};

const usage = "usage: node bundle.mjs <plotly|replay3d> <entry.js> <node_modules dir> <output.js>";
if (process.argv.length !== 6 || !(process.argv[2] in bundles)) {
  console.error(usage);
  process.exit(2);
}
const name = process.argv[2];
const bundle = bundles[name];
const [entry, nodeModules, output] = process.argv.slice(3).map((p) => path.resolve(p));
const require = createRequire(path.join(nodeModules, "fullarm-bundle.js"));
let esbuild;
let version;
try {
  esbuild = require("esbuild");
  version = JSON.parse(readFileSync(path.join(nodeModules, bundle.packageName, "package.json"), "utf8")).version;
} catch (error) {
  console.error(`bundle ${name}: ${error.message}: run npm ci in the repository (scripts/setup-deps does it)`);
  process.exit(1);
}

const result = esbuild.buildSync({
  entryPoints: [entry],
  nodePaths: [nodeModules],
  bundle: true,
  minify: true,
  format: "iife",
  legalComments: "none",
  ...bundle.options,
  banner: { js: bundle.banner(version) },
  write: false,
  logLevel: "warning",
});
const text = result.outputFiles[0].text;
const lower = text.toLowerCase();
if (lower.includes("</script") || lower.includes("<script")) {
  console.error(`bundle ${name}: the bundle contains a <script> tag and cannot be inlined`);
  process.exit(1);
}
writeFileSync(output, text);
console.log(`bundle ${name}: ${output} (${text.length} bytes, ${bundle.packageName} ${version})`);
