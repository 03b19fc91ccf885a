// fullarm report.html chart loader: inlined into every report at build time, after plotly.js.
//
// The chart figures (Plotly data + layout, built by fullarm::reports in C++) live in the JSON
// script element with id "fullarm-report-data" (this file itself must not contain script
// tags). Every element with a data-chart attribute names its figure; once Plotly has drawn it
// the element gets data-rendered="true" (or "error", with the message shown in its place).
(function () {
  "use strict";

  var config = {
    displaylogo: false,
    responsive: true,
    modeBarButtonsToRemove: ["select2d", "lasso2d"],
    toImageButtonOptions: { format: "svg" }
  };

  function fail(element, message) {
    element.setAttribute("data-rendered", "error");
    element.textContent = "";
    var note = document.createElement("p");
    note.className = "chart-error";
    note.textContent = "Chart not drawn: " + message;
    element.appendChild(note);
    console.error("fullarm report: chart " + element.getAttribute("data-chart") + ": " + message);
  }

  function render() {
    var charts = document.querySelectorAll("[data-chart]");
    var figures;
    try {
      figures = JSON.parse(document.getElementById("fullarm-report-data").textContent).charts;
    } catch (error) {
      charts.forEach(function (element) { fail(element, "bad chart data: " + error); });
      return;
    }
    if (typeof Plotly === "undefined") {
      charts.forEach(function (element) { fail(element, "plotly.js did not load"); });
      return;
    }
    charts.forEach(function (element) {
      var id = element.getAttribute("data-chart");
      var figure = figures[id];
      if (!figure) {
        fail(element, "no figure data for " + id);
        return;
      }
      var options = Object.assign({}, config, {
        toImageButtonOptions: { format: "svg", filename: id }
      });
      Plotly.newPlot(element, figure.data, figure.layout, options).then(
        function () { element.setAttribute("data-rendered", "true"); },
        function (error) { fail(element, String(error)); });
    });
  }

  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", render);
  } else {
    render();
  }
})();
