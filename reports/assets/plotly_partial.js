// The plotly.js of fullarm reports: its core (which holds the scatter trace) and the heatmap
// trace, the only trace types fullarm::reports draws (docs/reports.md). bundle_plotly.mjs
// bundles it at build time; the bundle's global is `Plotly`.
var Plotly = require("plotly.js/lib/core");

Plotly.register([require("plotly.js/lib/heatmap")]);

module.exports = Plotly;
