// ConceptBot page: start a run, then show each module's results as the server streams them.
"use strict";

const $ = (id) => document.getElementById(id);
const el = (tag, attrs = {}, ...children) => {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  for (const c of children) node.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return node;
};
const list = (text) => text.split(",").map((s) => s.trim()).filter(Boolean);
let options = null;
let source = null;

function setStatus(text, kind = "") {
  const s = $("status");
  s.textContent = text;
  s.className = kind;
}

function busy(on) {
  $("run").disabled = on;
  $("run").textContent = on ? "Planning…" : "Plan";
}

async function loadScene(name) {
  const r = await fetch(`/api/scenes/${encodeURIComponent(name)}`);
  const scene = await r.json();
  $("pickable").value = scene.pickable_objects.join(", ");
  $("destinations").value = scene.destinations.join(", ");
  const both = new Set([...scene.pickable_objects, ...scene.destinations]);
  $("others").value = scene.objects.filter((o) => !both.has(o)).join(", ");
  $("objects-box").dataset.edited = "";
}

function fill(select, values, chosen) {
  select.replaceChildren(...values.map((v) => el("option", v === chosen ? { value: v, selected: "" } : { value: v }, v)));
}

async function init() {
  options = await (await fetch("/api/options")).json();
  fill($("scene"), options.scenes, options.default_scene);
  fill($("config"), options.configs, options.default_config);
  fill($("backend"), options.backends, options.backends[0]);
  $("simulate").checked = options.simulator;
  $("simulate-label").hidden = !options.simulator;
  $("scene").addEventListener("change", () => loadScene($("scene").value));
  for (const id of ["pickable", "destinations", "others"]) {
    $(id).addEventListener("input", () => { $("objects-box").dataset.edited = "yes"; });
  }
  await loadScene(options.default_scene);
  $("ask").addEventListener("submit", start);
}

function clear() {
  for (const id of ["question-box", "refusal", "plan-box", "sim-box", "ope-box", "urp-box", "goal-box", "steps-box"]) $(id).hidden = true;
  for (const id of ["plan", "confidence", "properties", "relations", "keyword-relations", "targets", "decisions", "risk-checks", "steps", "sim-pictures"]) $(id).replaceChildren();
}

async function start(event) {
  event.preventDefault();
  const body = {
    request: $("request").value,
    config: $("config").value,
    backend: $("backend").value,
    risk: $("risk").checked,
    simulate: $("simulate").checked,
  };
  if ($("objects-box").dataset.edited === "yes") {
    const pickable = list($("pickable").value);
    const destinations = list($("destinations").value);
    body.objects = { objects: [...pickable, ...destinations, ...list($("others").value)], pickable_objects: pickable, destinations };
  } else {
    body.scene = $("scene").value;
  }
  clear();
  busy(true);
  setStatus("starting…", "busy");
  const r = await fetch("/api/runs", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  const reply = await r.json();
  if (!r.ok) {
    busy(false);
    const detail = typeof reply.detail === "string" ? reply.detail : JSON.stringify(reply.detail);
    setStatus(`Not started: ${detail}`, "error");
    return;
  }
  listen(reply.id);
}

function listen(id) {
  if (source) source.close();
  source = new EventSource(`/api/runs/${id}/events`);
  source.onmessage = (message) => handle(id, JSON.parse(message.data));
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) busy(false); };
}

function handle(id, e) {
  switch (e.type) {
    case "status": setStatus(e.message, "busy"); break;
    case "ope": showOpe(e.data); break;
    case "urp": showUrp(e.data); break;
    case "step": showStep(e.data); break;
    case "goal": showGoal(e.data); break;
    case "decisions": showDecisions(e.data.decisions); break;
    case "risk": showRisk(e.data.checks); break;
    case "plan": showPlan(e); break;
    case "question": showQuestion(id, e.question); break;
    case "sim": showSim(id, e); break;
    case "error":
      setStatus(`Error: ${e.message}${e.hint ? " — " + e.hint : ""}`, "error");
      source.close(); busy(false); break;
    case "done":
      setStatus("Done.");
      source.close(); busy(false); break;
  }
}

function relationsTable(retrievals, perConcept = 8) {
  const box = el("div");
  for (const [concept, r] of Object.entries(retrievals)) {
    const table = el("table", {}, el("tr", {}, el("th", {}, `${concept}${r.match && r.match !== "exact" ? " (" + r.match + " match)" : ""}`), el("th", {}, "similarity"), el("th", {}, "source")));
    const edges = r.edges.slice().sort((a, b) => b.similarity - a.similarity).slice(0, perConcept);
    if (!edges.length) table.append(el("tr", {}, el("td", { class: "dim" }, "no relations in the graph")));
    for (const edge of edges) {
      table.append(el("tr", { class: edge.kept ? "kept" : "dropped" }, el("td", {}, edge.relation), el("td", {}, edge.similarity.toFixed(3)), el("td", {}, edge.source)));
    }
    box.append(table);
  }
  return box;
}

function showOpe(ope) {
  $("ope-box").hidden = false;
  $("ope-mode").textContent = `mode: ${ope.mode} (${ope.why})`;
  const names = Object.keys(ope.objects);
  const keys = names.length ? Object.keys(ope.objects[names[0]].values).filter((k) => k !== "object") : [];
  const table = $("properties");
  table.append(el("tr", {}, el("th", {}, "object"), ...keys.map((k) => el("th", {}, k))));
  for (const name of names) {
    const values = ope.objects[name].values;
    const cells = keys.map((k) => {
      let v = values[k];
      if (Array.isArray(v)) v = v.map((x) => (typeof x === "object" ? `${x.object} (${x.score})` : x)).join(", ");
      return el("td", k === "dangerous" ? { class: `risk-${v}` } : {}, v ?? "");
    });
    table.append(el("tr", {}, el("td", {}, name), ...cells));
  }
  $("relations").append(relationsTable(ope.retrieval));
}

function showUrp(urp) {
  $("urp-box").hidden = false;
  $("keywords").textContent = urp.keywords.join(", ") || "(none)";
  $("reasoning").textContent = urp.reasoning;
  $("commands").textContent = urp.commands.join("; ") || "(none)";
  $("keyword-relations").append(relationsTable(urp.keyword_relations, 6));
  if (urp.refused) showRefusal(urp.refusal_reason || "judged unsafe");
}

function showStep(step) {
  $("steps-box").hidden = false;
  const box = el("div", { class: "step" }, el("h3", {}, `Step ${step.index}: ${step.chosen}`));
  const top = Math.max(...step.candidates.map((c) => c.combined), 1e-9);
  for (const c of step.candidates) {
    // Width through element.style: the Content-Security-Policy refuses style="..." attributes.
    const fill = el("div", { class: "fill" });
    fill.style.width = `${(100 * c.combined) / top}%`;
    const row = el("div", { class: c.action === step.chosen ? "bar chosen" : "bar" },
      el("span", {}, c.action), fill, el("span", {}, c.combined.toFixed(3)));
    row.title = `LLM ${c.llm.toFixed(3)} × affordance ${c.affordance.toFixed(2)}`;
    box.append(row);
  }
  $("steps").append(box);
}

function showGoal(goal) {
  $("goal-box").hidden = false;
  $("targets").replaceChildren(...goal.targets.map((t) => el("li", {},
    `→ ${t.to}: ${t.count} (${t.how}${t.named.length ? ", named: " + t.named.join(", ") : ""}` +
    `${t.criterion ? ", objects that fit “" + t.criterion + "”" : ""}` +
    `${t.dish ? ", a dish the graph knows: " + t.dish : ""}${t.rest ? ", the rest" : ""}` +
    `${t.part ? ", " + t.part : ""})`)));
  if (goal.stack) $("targets").append(el("li", {}, "stack the objects"));
  // Where the model said the request plainly first (pipeline/goal/aided.py), which reading won.
  const readings = {both: "its own words read the same", plain: "read from this plain form",
                    words: "read from its own words; this plain form read otherwise",
                    sampled: "read from a sampled plain form, as you chose"};
  if (goal.reading) $("targets").append(el("li", {class: "plain"},
    `said plainly by the model: “${goal.plain}” (${readings[goal.reading]})`));
  // Where it reads two ways or more: each reading with P(it is the one meant), whether asked or not.
  const kinds = {taken: "taken", other: "dropped", sampled: "sampled"};
  if (goal.readings && goal.readings.length > 1) $("targets").append(el("li", {class: "plain"},
    `readings (${goal.step}): ` + goal.readings.map((r) =>
      `${kinds[r.kind]} “${r.text}” ${r.p === null ? "P ?" : "P " + r.p.toFixed(2)}`).join("; ") +
    (typeof goal.preference === "number"
      ? `; the model prefers the ${goal.preference >= 0 ? "taken" : "dropped"} one by ${Math.abs(goal.preference).toFixed(2)} nats`
      : "")));
}

function showDecisions(decisions) {
  for (const d of decisions.filter((x) => x.decided)) {
    // The name ranking (all objects in one question) exists only for targets taking N objects.
    const names = d.objects.some((o) => "name_score" in o);
    // Combined decisions carry the model's own log-odds and the graph's evidence statements.
    const combined = d.objects.some((o) => "model" in o);
    // The graph's evidence: of a combination, or what the graph states an object is for (a need).
    const evidenced = combined || d.objects.some((o) => o.evidence);
    // Where the combination asked with the model's own description of each object too.
    const described = d.objects.some((o) => "described" in o);
    const table = el("table", {}, el("tr", {}, el("th", {}, `for the ${d.to}`), el("th", {}, "P(yes)"),
      el("th", {}, "score"), ...(combined ? [el("th", {}, "model")] : []), ...(names ? [el("th", {}, "name")] : []),
      el("th", {}, evidenced ? "graph evidence" : "graph facts in the question"),
      ...(described ? [el("th", {}, "the model's description")] : [])));
    for (const o of d.objects.slice().sort((a, b) => b.score - a.score)) {
      const said = evidenced && o.evidence ? o.evidence.statements : o.facts;
      table.append(el("tr", { class: o.score > 0 ? "kept" : "dropped" }, el("td", {}, o.object),
        el("td", {}, o.p_yes.toFixed(2)), el("td", {}, o.score.toFixed(2)),
        ...(combined ? [el("td", {}, "model" in o ? o.model.toFixed(2) : "")] : []),
        ...(names ? [el("td", {}, o.name_score.toFixed(2))] : []), el("td", {}, said.join("; ")),
        ...(described ? [el("td", {}, o.described || "")] : [])));
    }
    if (d.context && d.context.length) $("decisions").append(el("p", {}, "facts about the request: " + d.context.join("; ")));
    $("decisions").append(table);
  }
}

function showRisk(checks) {
  $("risk-checks").replaceChildren(...checks.map((c) => el("li", { class: c.dropped ? "error" : "kept" },
    // p_unsafe is null for a vetoed move (no score was needed, or none could be had): say why instead.
    `${c.move}: ${c.p_unsafe === null ? "no score" : "P(unsafe) " + c.p_unsafe.toFixed(2)}` +
    `${c.dropped ? " — dropped: " + (c.veto ? "vetoed, " + c.veto : c.why) : " — ok"}`)));
}

function showQuestion(id, question) {
  // The planner is unsure: it waits for this answer (text only: the question quotes scene names).
  $("question-box").hidden = false;
  $("question-text").textContent = question.text;
  const send = (answer) => async () => {
    $("question-box").hidden = true;
    // Said first: the plan (and "Done.") may arrive on the event stream before this reply does.
    setStatus(`Answered ${answer}.`, "busy");
    const r = await fetch(`/api/runs/${id}/answer`, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify({ answer }) });
    if (!r.ok) setStatus("The question was no longer open.", "error");
  };
  const listed = question.kind !== "confirm";
  $("confirm-buttons").hidden = listed;
  $("choose-box").hidden = !listed;
  if (listed) {
    // One box per object: checkboxes for "which of these go", radio buttons for "which one";
    // the ticked ones go to the target, none ticked is "none".
    const type = question.kind === "choose" ? "checkbox" : "radio";
    // A which-one question's others follow, marked: the person may pick what the set missed.
    const others = question.others || [];
    $("choose-options").replaceChildren(...[...question.options, ...others].map((name, i) => el("li", i < question.options.length ? {} : { class: "other" },
      el("input", { type, name: "choose", id: `choose-${i}`, value: name }), el("label", { for: `choose-${i}` }, ` ${i === question.options.length ? "or another: " : ""}${name}`))));
    $("answer-chosen").textContent = { one: "This one", reading: "This is what I meant" }[question.kind] || "These go";
    $("answer-none").onclick = send("none");
    $("answer-chosen").onclick = () => {
      const ticked = [...$("choose-options").querySelectorAll("input:checked")].map((b) => b.value);
      send(ticked.length ? ticked.join(", ") : "none")();
    };
  } else {
    $("answer-yes").onclick = send("yes");
    $("answer-no").onclick = send("no");
  }
}

function showRefusal(reason) {
  $("refusal").hidden = false;
  $("refusal-reason").textContent = reason;
}

function showPlan(e) {
  $("plan-box").hidden = false;
  $("plan").replaceChildren(...e.plan.map((a) => el("li", {}, a)));
  const total = e.usage.total;
  if (total) $("usage").textContent = `${total.latency_s.toFixed(1)} s, ${total.prompt_tokens + total.completion_tokens} tokens, ${total.calls} LLM calls`;
  // The plan's confidence and where it is lost (absent for planners without calibrated decisions).
  const shares = (e.confidence_by_target || []).map((t) => `the ${t.to} ${t.confidence.toFixed(2)}`).join(", ");
  $("confidence").textContent = typeof e.confidence === "number"
    ? `Confidence ${e.confidence.toFixed(2)} that its calibrated decisions are all right${shares ? " (" + shares + ")" : ""}` : "";
  // Thresholds fitted for another model do not keep the coverage they promise: say so.
  const c = e.calibration;
  if (c && !c.own) $("confidence").textContent += ` — the thresholds were fitted for ${c.fitted_for}, not for ${c.model}: the ${c.coverage} coverage is not promised (conceptbot calibrate --conformal fits this model's own)`;
  // Things used together: "would they also need the X with the Y?" and whether it went too.
  $("risk-checks").append(...(e.companions || []).map((c) => el("li", { class: c.used ? "kept" : "" },
    `used with the ${c.anchor}? the ${c.object}: ${c.p === null ? "no answer" : "P " + c.p.toFixed(2)}` +
    (c.graph ? ` (graph: ${c.graph})` : "") + (c.used ? " — goes too" : " — not taken"))));
  if (e.refused) showRefusal(e.reason || "judged unsafe");
}

function showSim(id, e) {
  $("sim-box").hidden = false;
  $("sim-verdict").textContent = e.verdict;
  $("sim-verdict").className = e.ok ? "kept" : "error";
  $("sim-pictures").replaceChildren(...e.files.map((f) => el("img", { src: `/api/runs/${id}/files/${f}`, alt: f })));
}

init().catch((err) => setStatus(`Could not load the page: ${err}`, "error"));
