"""The monitor's web page, one self-contained HTML document (no external scripts or fonts, so
it works on a robot's network with no internet).

It listens to ``/events`` (Server-Sent Events) and redraws from each snapshot: the map as SVG
(nodes at their dead-reckoned x, y; the current node and the goal highlighted; nodes with
look-alikes ringed), the robot's state and the recent events. Every robot-provided string goes
in through ``textContent``, never as HTML. Element ids and classes are what the tests read.
"""

from __future__ import annotations

PAGE = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>tslam monitor</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
 body { font-family: system-ui, sans-serif; margin: 0; display: flex; flex-wrap: wrap; }
 #mapbox { flex: 3 1 480px; padding: 8px; }
 #side { flex: 1 1 300px; padding: 8px; font-size: 14px; }
 svg { width: 100%; height: 75vh; background: #fafafa; border: 1px solid #ccc; }
 .edge { stroke: #555; stroke-width: 2; vector-effect: non-scaling-stroke; }
 .node { stroke: #222; stroke-width: 1; vector-effect: non-scaling-stroke; }
 .node.meet { fill: #4a90d9; }
 .node.boundary { fill: #aaa; }
 .node.unexplored { fill: #f5a623; }
 .node.ambiguous { stroke: #d0021b; stroke-width: 3; stroke-dasharray: 3 2; }
 .node.goal { stroke: #417505; stroke-width: 4; }
 .node.current { fill: #d0021b; }
 .label { fill: #333; }
 #pose { fill: none; stroke: #7b1fa2; stroke-width: 2; vector-effect: non-scaling-stroke; }
 table { border-collapse: collapse; }
 th { text-align: left; padding-right: 10px; font-weight: normal; color: #555; }
 .online { color: #417505; font-weight: bold; }
 .offline { color: #d0021b; font-weight: bold; }
 #legend { font-size: 12px; color: #555; }
 #events { padding-left: 18px; max-height: 30vh; overflow-y: auto; }
 #reply.refused, #reply.error { color: #d0021b; }
 #reply.accepted { color: #417505; }
 button { margin: 2px; }
</style>
</head>
<body data-updates="0">
<div id="mapbox">
 <h2>Robot <span id="robot">?</span> <span id="st-online" class="offline">connecting</span></h2>
 <svg id="map" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100"
      preserveAspectRatio="xMidYMid meet">
  <g id="edges"></g><g id="nodes"></g><g id="labels"></g><path id="pose" d=""></path>
 </svg>
 <div id="legend">red: current node &middot; orange: exits not yet explored &middot;
  blue: explored meet point, grey: boundary point &middot; dashed red ring: has look-alikes
  &middot; green ring: goal &middot; arrow: dead-reckoned pose</div>
 <div id="conn">connecting to the monitor&hellip;</div>
</div>
<div id="side">
 <table id="state">
  <tr><th>behaviour</th><td id="st-behaviour">-</td></tr>
  <tr><th>mode</th><td id="st-mode">-</td></tr>
  <tr><th>paused</th><td id="st-paused">-</td></tr>
  <tr><th>done</th><td id="st-done">-</td></tr>
  <tr><th>current node</th><td id="st-node">-</td></tr>
  <tr><th>current edge</th><td id="st-edge">-</td></tr>
  <tr><th>goal</th><td id="st-goal">-</td></tr>
  <tr><th>pose (dead-reckoned)</th><td id="st-pose">-</td></tr>
  <tr><th>hypotheses</th><td id="st-hyp">-</td></tr>
  <tr><th>map</th><td id="st-map">-</td></tr>
  <tr><th>gaps repaired</th><td id="st-gaps">-</td></tr>
  <tr><th>error</th><td id="st-error">-</td></tr>
 </table>
 <h3>Commands</h3>
 <div>
  <button data-op="pause">pause</button>
  <button data-op="resume">resume</button>
  <button data-op="stop">stop</button>
  <button data-op="explore">explore</button>
 </div>
 <div>
  <label>node <input id="goto-node" type="number" min="0" step="1" style="width:5em"></label>
  <button data-op="goto">go to node</button>
 </div>
 <div id="reply"></div>
 <h3>Recent events</h3>
 <ol id="events"></ol>
</div>
<script>
"use strict";
const SVGNS = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);
const show = (v) => (v === null || v === undefined) ? "-" : String(v);

function setText(id, v) { $(id).textContent = show(v); }

function svgEl(tag, attrs) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  return e;
}

function drawMap(view) {
  const nodes = view.map.nodes, edges = view.map.edges, st = view.state;
  const pts = nodes.map((n) => [n.x, n.y]);
  if (st && st.x !== null && st.y !== null) pts.push([st.x, st.y]);
  let minx = 0, maxx = 1, miny = 0, maxy = 1;
  if (pts.length) {
    minx = Math.min(...pts.map((p) => p[0])); maxx = Math.max(...pts.map((p) => p[0]));
    miny = Math.min(...pts.map((p) => p[1])); maxy = Math.max(...pts.map((p) => p[1]));
  }
  const pad = 1.0, w = Math.max(maxx - minx, 1) + 2 * pad, h = Math.max(maxy - miny, 1) + 2 * pad;
  // World y points up, SVG y down: flip by drawing at -y.
  $("map").setAttribute("viewBox", `${minx - pad} ${-maxy - pad} ${w} ${h}`);
  const r = Math.max(w, h) / 80;
  const byId = new Map(nodes.map((n) => [n.id, n]));
  const ge = $("edges"), gn = $("nodes"), gl = $("labels");
  ge.replaceChildren(); gn.replaceChildren(); gl.replaceChildren();
  for (const e of edges) {
    const a = byId.get(e.u), b = byId.get(e.v);
    if (!a || !b) continue;
    ge.appendChild(svgEl("line", {class: "edge", "data-id": e.id,
      x1: a.x, y1: -a.y, x2: b.x, y2: -b.y}));
  }
  for (const n of nodes) {
    const cls = ["node", n.kind];
    if (n.unexplored > 0) cls.push("unexplored");
    if (n.ambiguous_with && n.ambiguous_with.length) cls.push("ambiguous");
    if (st && st.goal_node === n.id) cls.push("goal");
    if (st && st.current_node === n.id) cls.push("current");
    const c = svgEl("circle", {class: cls.join(" "), "data-id": n.id, cx: n.x, cy: -n.y, r: r});
    const t = svgEl("title", {});
    t.textContent = `node ${n.id} (${n.kind}, degree ${n.degree}, ` +
      `${n.unexplored} unexplored, clearance ${n.clearance_m.toFixed(2)} m)` +
      (n.ambiguous_with.length ? `; looks like ${n.ambiguous_with.join(", ")}` : "");
    c.appendChild(t);
    gn.appendChild(c);
    const l = svgEl("text", {class: "label", x: n.x + 1.3 * r, y: -n.y - 1.3 * r,
      "font-size": 2.2 * r});
    l.textContent = String(n.id);
    gl.appendChild(l);
  }
  if (st && st.x !== null && st.y !== null && st.theta !== null) {
    // A small arrowhead at the dead-reckoned pose.
    const L = 2.5 * r, a = st.theta, x = st.x, y = -st.y;
    const p = (d, ang) => `${x + d * Math.cos(ang)},${y - d * Math.sin(ang)}`;
    $("pose").setAttribute("d",
      `M${p(L, a)} L${p(L * 0.6, a + 2.4)} L${p(L * 0.6, a - 2.4)} Z`);
  } else {
    $("pose").setAttribute("d", "");
  }
}

function drawState(view) {
  setText("robot", view.robot);
  const on = $("st-online");
  on.textContent = view.online ? "online" : "offline";
  on.className = view.online ? "online" : "offline";
  const st = view.state || {};
  setText("st-behaviour", st.behaviour);
  setText("st-mode", st.mode);
  setText("st-paused", st.paused === undefined ? null : (st.paused ? "yes" : "no"));
  setText("st-done", st.done === undefined ? null : (st.done ? "yes" : "no"));
  setText("st-node", st.current_node);
  setText("st-edge", st.current_edge);
  setText("st-goal", st.goal_node);
  setText("st-pose", (st.x === undefined || st.x === null) ? null :
    `x ${st.x.toFixed(2)} m, y ${st.y.toFixed(2)} m, ` +
    `${(Math.atan2(Math.sin(st.theta), Math.cos(st.theta)) * 180 / Math.PI).toFixed(0)} deg`);
  setText("st-hyp", (st.hypotheses && st.hypotheses.length) ? st.hypotheses.join(", ") : null);
  setText("st-map", `${view.map.nodes.length} nodes, ${view.map.edges.length} edges, ` +
    `${view.map.nodes.filter((n) => n.unexplored > 0).length} with unexplored exits`);
  setText("st-gaps", view.gaps);
  setText("st-error", st.error);
  const ol = $("events");
  ol.replaceChildren();
  for (const ev of view.events.slice(-20).reverse()) {
    const li = document.createElement("li");
    li.className = "event";
    li.textContent = `[${ev.seq}] t=${Number(ev.stamp_s).toFixed(1)} ${ev.kind}: ${ev.text}`;
    ol.appendChild(li);
  }
}

function render(view) {
  drawMap(view);
  drawState(view);
  document.body.dataset.updates = String(Number(document.body.dataset.updates) + 1);
}

async function sendCommand(op) {
  const body = {op: op};
  if (op === "goto") {
    const v = $("goto-node").value;
    body.node = v === "" ? null : Number(v);
  }
  const out = $("reply");
  out.className = ""; out.textContent = `${op}: sending...`;
  try {
    const resp = await fetch("/command", {method: "POST",
      headers: {"Content-Type": "application/json"}, body: JSON.stringify(body)});
    const data = await resp.json();
    if (!resp.ok) {
      out.className = "error"; out.textContent = `${op}: ${data.error}`;
    } else {
      out.className = data.accepted ? "accepted" : "refused";
      out.textContent = `${op}: ${data.accepted ? "accepted" : "refused"}` +
        (data.reason ? ` (${data.reason})` : "");
    }
  } catch (err) {
    out.className = "error"; out.textContent = `${op}: monitor unreachable (${err})`;
  }
}

for (const b of document.querySelectorAll("button[data-op]")) {
  b.addEventListener("click", () => sendCommand(b.dataset.op));
}

const source = new EventSource("/events");
source.onopen = () => { $("conn").textContent = "live"; };
source.onerror = () => {
  // EventSource reconnects by itself; say so rather than show stale data as live.
  $("conn").textContent = "monitor unreachable, retrying...";
  const on = $("st-online"); on.textContent = "unknown"; on.className = "offline";
};
source.onmessage = (msg) => { render(JSON.parse(msg.data)); $("conn").textContent = "live"; };
</script>
</body>
</html>
"""
