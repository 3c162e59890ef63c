// Benchmark results page: the latest report tables (Markdown from the server) and their charts.
"use strict";

function markdownToNodes(text) {
  const nodes = [];
  let table = null;
  for (const line of text.split("\n")) {
    if (line.startsWith("|")) {
      const cells = line.split("|").slice(1, -1).map((c) => c.trim());
      if (cells.every((c) => /^-+$/.test(c))) continue;
      if (!table) { table = document.createElement("table"); nodes.push(table); }
      const row = table.insertRow();
      for (const c of cells) {
        const cell = document.createElement(table.rows.length === 1 ? "th" : "td");
        cell.textContent = c.replace(/\*\*/g, "");
        row.append(cell);
      }
    } else {
      table = null;
      if (line.trim()) { const p = document.createElement("p"); p.textContent = line; nodes.push(p); }
    }
  }
  return nodes;
}

async function init() {
  const main = document.getElementById("reports");
  const { reports } = await (await fetch("/api/results")).json();
  main.replaceChildren();
  if (!reports.length) {
    main.append(Object.assign(document.createElement("p"), { textContent: "No reports yet: run `conceptbot bench report RESULTS` or `conceptbot safebench report RESULTS`." }));
  }
  for (const r of reports) {
    const section = document.createElement("section");
    section.className = "report";
    const h = document.createElement("h2");
    h.textContent = r.title;
    section.append(h, ...markdownToNodes(r.markdown));
    if (r.chart) section.append(Object.assign(document.createElement("img"), { src: r.chart, alt: `${r.title} chart` }));
    main.append(section);
  }
}

init().catch((err) => { document.getElementById("reports").textContent = `Could not load the results: ${err}`; });
