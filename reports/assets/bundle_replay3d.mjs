// Bundles the 3D replay of fullarm reports (replay3d.js with the parts of three.js it imports)
// into one minified script with esbuild; the build runs it (reports/CMakeLists.txt).
//
// Usage: node bundle_replay3d.mjs <entry.js> <node_modules dir> <output.js>
//
// Fails (exit status 1) when a package is missing or the bundle holds a <script> tag (it is
// inlined into a <script> element of every report.html that holds a 3D replay).
import { createRequire } from "node:module";
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";

if (process.argv.length !== 5) {
  console.error("usage: node bundle_replay3d.mjs <entry.js> <node_modules dir> <output.js>");
  process.exit(2);
}
const [entry, nodeModules, output] = process.argv.slice(2).map((p) => path.resolve(p));
const require = createRequire(path.join(nodeModules, "fullarm-bundle.js"));
let esbuild;
let threePackage;
try {
  esbuild = require("esbuild");
  threePackage = JSON.parse(readFileSync(path.join(nodeModules, "three", "package.json"), "utf8"));
} catch (error) {
  console.error(`bundle_replay3d: ${error.message}: run npm ci in the repository (scripts/setup-deps does it)`);
  process.exit(1);
}

const result = esbuild.buildSync({
  entryPoints: [entry],
  nodePaths: [nodeModules],
  bundle: true,
  minify: true,
  format: "iife",
  target: "es2018",
  legalComments: "none",
  banner: {
    js: `/*! three.js r${threePackage.version.split(".")[1]} | Copyright 2010-2025 three.js authors | MIT licence */`,
  },
  write: false,
  logLevel: "warning",
});
const text = result.outputFiles[0].text;
const lower = text.toLowerCase();
if (lower.includes("</script") || lower.includes("<script")) {
  console.error("bundle_replay3d: the bundle contains a <script> tag and cannot be inlined");
  process.exit(1);
}
writeFileSync(output, text);
console.log(`bundle_replay3d: ${output} (${text.length} bytes, three.js ${threePackage.version})`);
