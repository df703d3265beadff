// Live view: polls the JSON API once a second and renders schematic, plot, devices, clients, clock.
// After a whole update has been rendered, <body data-t> holds the plant time it shows.
"use strict";

const PERIOD_MS = 1000;
const DEFAULT_SIGNALS = ["storage.T_sensor_10", "storage.T_sensor_5", "storage.T_sensor_1",
  "chp.T_sup", "boiler.T_sup", "mixer.T_sup", "zone.T_room"];
const COLOURS = ["#dc2626", "#ea580c", "#2563eb", "#16a34a", "#9333ea", "#0891b2", "#ca8a04",
  "#db2777", "#4b5563", "#65a30d"];
const RUNNING = { chp: ["1", "2", "3", "4"], boiler: ["1", "3", "4"] };
const ALARM = ["5", "8"];

let chosen = JSON.parse(localStorage.getItem("twin.signals") || "null") || DEFAULT_SIGNALS;
let plot = null, plotKey = "", startEpoch = 0, tanksBuilt = false, devicesBuilt = false;

const $ = (sel) => document.querySelector(sel);
const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c]));

function fmt(v, digits, scale, unit) {
  if (v === null || v === undefined) return "–";
  return (v * (scale || 1)).toFixed(digits) + (unit || "");
}

const isoTime = (ts) => new Date(ts * 1000).toISOString().replace("T", " ");

function tempColour(T) {
  if (T === null || T === undefined) return "#9ca3af";
  const f = Math.max(0, Math.min(1, (T - 15) / (80 - 15)));
  return `hsl(${Math.round(230 * (1 - f))}, 70%, ${45 - 5 * f}%)`;
}

function buildTank(id, x, y, w, h) {
  const g = document.getElementById(id), ns = "http://www.w3.org/2000/svg", dh = h / 10;
  let html = "";
  for (let k = 10; k >= 1; k--) {
    const yy = y + (10 - k) * dh;
    html += `<rect class="layer" data-fill-signal="${id}.T_sensor_${k}" x="${x}" y="${yy}" width="${w}" height="${dh}"/>` +
      `<text class="idx" x="${x + 5}" y="${yy + dh / 2 + 4}">${k}</text>` +
      `<text class="val" text-anchor="end" x="${x + w - 5}" y="${yy + dh / 2 + 5}" data-signal="${id}.T_sensor_${k}" data-digits="1" data-unit="${w > 80 ? " °C" : ""}"></text>`;
  }
  html += `<rect class="shell" x="${x}" y="${y}" width="${w}" height="${h}" rx="4"/>`;
  g.innerHTML = html;
  void ns;
}

function renderSignals(sig) {
  if (!tanksBuilt) {
    buildTank("storage", 290, 40, 90, 400);
    buildTank("dhw_storage", 455, 140, 70, 250);
    tanksBuilt = true;
    $("#signal-names").innerHTML = Object.keys(sig.values).map((n) => `<option value="${esc(n)}">`).join("");
  }
  document.querySelectorAll("[data-signal]").forEach((el) => {
    const d = el.dataset;
    el.textContent = fmt(sig.values[d.signal], +(d.digits || 1), d.scale ? +d.scale : 1, d.unit);
  });
  document.querySelectorAll("[data-fill-signal]").forEach((el) => {
    el.setAttribute("fill", tempColour(sig.values[el.dataset.fillSignal]));
  });
  document.querySelectorAll("[data-state]").forEach((el) => {
    const name = el.dataset.state, v = sig.values[name];
    const code = v === null || v === undefined ? "" : String(Math.round(v));
    const table = (sig.states || {})[name] || {};
    el.textContent = code === "" ? "–" : (table[code] || `mode ${code}`);
    const box = el.closest(".gen"), family = name.split(".")[0];
    if (box) {
      box.classList.toggle("running", (RUNNING[family] || []).includes(code));
      box.classList.toggle("alarm", ALARM.includes(code));
    }
  });
}

function renderClock(c) {
  $("#house").textContent = c.house;
  startEpoch = c.start ? Date.parse(c.start + "T00:00:00Z") / 1000 : 0;
  const when = isoTime(startEpoch + c.t).slice(0, 19);
  const day = Math.floor(c.t / 86400);
  $("#sim-time").textContent = `${when} (t = ${c.t.toFixed(0)} s, day ${day})`;
  $("#clock-mode").textContent = c.mode === "paced" ? `paced ${c.factor}× · dt ${c.dt} s` : `lock-step · dt ${c.dt} s`;
  const l = c.lateness || {};
  $("#lateness").textContent = l.steps ? `lateness median ${l.median_ms.toFixed(2)} ms · p99 ${l.p99_ms.toFixed(2)} ms · max ${l.max_ms.toFixed(1)} ms (${l.steps} steps)`
    : `${c.steps} steps` + (c.last_step_ms !== null ? ` · last step ${c.last_step_ms.toFixed(2)} ms` : "");
}

function renderDevices(data) {
  const root = $("#devices");
  if (!devicesBuilt) {
    root.innerHTML = data.devices.map((d) => `<div class="device" id="dev-${esc(d.id)}">
      <h3>${esc(d.id)} <span class="small">${esc(d.vendor)} ${esc(d.model)} · unit ${d.unit_id} · node 0x${d.node_id.toString(16)}</span></h3>
      <div class="meta"></div>
      <table><thead><tr><th>point</th><th>address</th><th class="num">raw</th><th class="num">value</th><th>unit</th><th>binding</th></tr></thead><tbody>
      ${d.points.map((p) => `<tr id="pt-${esc(d.id)}-${esc(p.name)}"><td>${esc(p.name)}</td><td>${p.table} ${p.address}</td>
        <td class="num raw"></td><td class="num value"></td><td>${esc(p.unit)}</td><td class="small">${esc(p.binding)}</td></tr>`).join("")}
      </tbody></table></div>`).join("");
    $("#fault-device").innerHTML = data.devices.map((d) => `<option>${esc(d.id)}</option>`).join("");
    devicesBuilt = true;
  }
  for (const d of data.devices) {
    const card = document.getElementById(`dev-${d.id}`);
    if (!card) continue;
    const wd = d.watchdog ? `<span class="wd-${d.watchdog.state}">watchdog ${d.watchdog.state}` +
      (d.watchdog.remaining_s !== null ? ` (${d.watchdog.remaining_s.toFixed(0)} s left)` : "") + `</span>` : "no watchdog";
    const faults = [];
    if (d.tripped) faults.push(`tripped (code ${d.fault_code})`);
    for (const [p, f] of Object.entries(d.sensor_faults)) faults.push(`sensor ${p} ${f.kind}`);
    if (d.link_fault.mode !== "none") faults.push(`link ${d.link_fault.mode}`);
    card.querySelector(".meta").innerHTML = `${d.remote ? "remote" : "local"} · status 0x${d.status_word.toString(16).padStart(4, "0")} · ${wd}` +
      (faults.length ? ` · <span class="bad">${esc(faults.join(", "))}</span>` : "");
    for (const p of d.points) {
      const row = document.getElementById(`pt-${d.id}-${p.name}`);
      if (!row) continue;
      row.querySelector(".raw").textContent = p.refusal ? p.refusal : (p.raw === null ? "–" : String(p.raw));
      let v = p.value;
      if (typeof v === "number") v = p.type === "float32" ? v.toPrecision(6) : String(+v.toFixed(6));
      row.querySelector(".value").textContent = p.text ? `${v} ${p.text}` : (v === null ? "–" : v);
    }
  }
}

function renderClients(c) {
  const rows = Object.entries(c.clients).map(([name, a]) => `<tr><td>${esc(name)}</td><td>${a.requests}</td>
    <td>${a.poll_rate_hz.toFixed(2)}</td><td>${a.writes_accepted}</td>
    <td class="${Object.keys(a.writes_refused).length ? "bad" : ""}">${esc(Object.entries(a.writes_refused).map(([r, n]) => `${r} ×${n}`).join(", ") || "none")}</td></tr>`);
  $("#clients tbody").innerHTML = rows.join("") || `<tr><td colspan="5" class="small">no client has talked to the gateway yet</td></tr>`;
  const conns = Object.entries(c.connections).map(([tr, peers]) => `${tr}: ${peers.length ? peers.join(", ") : "no open connection"}`);
  const links = Object.entries(c.link_events).map(([k, n]) => `${k} ×${n}`);
  $("#connections").textContent = conns.join(" · ") + (links.length ? " · link: " + links.join(", ") : "");
  $("#watchdogs").innerHTML = Object.entries(c.watchdogs).map(([d, s]) => `<span class="wd-${s}">${esc(d)} ${s}</span>`).join(" · ") || "none";
  $("#events tbody").innerHTML = c.events.slice(0, 8).map((e) => {
    const what = e.kind === "write" ? (e.accepted ? `write ${e.point}` : `refused ${e.point}`) :
      e.kind === "fault" ? `fault ${e.fault}` : e.kind === "watchdog" ? `watchdog ${e.state}` : `${e.kind} ${e.event || ""}`;
    const detail = e.kind === "write" ? (e.accepted ? `raw ${e.raw} (${e.client})` : `${e.reason}: ${e.detail}`) : (e.point || e.reason || "");
    return `<tr class="${e.accepted === false ? "bad" : ""}"><td>${(e.t || 0).toFixed(0)}</td><td>${esc(e.device || "")}</td><td>${esc(what)}</td><td>${esc(detail)}</td></tr>`;
  }).join("");
}

function renderChips() {
  $("#chips").innerHTML = chosen.map((n, i) => `<span class="chip" style="background:${COLOURS[i % COLOURS.length]}" data-name="${esc(n)}" title="click to remove">${esc(n)} ×</span>`).join("");
  localStorage.setItem("twin.signals", JSON.stringify(chosen));
}

async function renderPlot() {
  if (!chosen.length) { if (plot) { plot.destroy(); plot = null; plotKey = ""; } return; }
  const h = await (await fetch(`/api/history?names=${encodeURIComponent(chosen.join(","))}`)).json();
  if (h.error) { chosen = chosen.filter((n) => h.error.indexOf(`'${n}'`) < 0); renderChips(); return; }
  const data = [h.t.map((t) => startEpoch + t), ...chosen.map((n) => h.series[n])];
  const key = chosen.join(",");
  const width = $("#plot-panel").clientWidth - 20;
  if (!plot || key !== plotKey) {
    if (plot) plot.destroy();
    plot = new uPlot({
      width, height: 380, tzDate: (ts) => uPlot.tzDate(new Date(ts * 1e3), "Etc/UTC"),
      series: [{ label: "time (UTC)", value: (u, ts) => ts === null ? "–" : isoTime(ts).slice(5, 16) },
        ...chosen.map((n, i) => ({ label: n, stroke: COLOURS[i % COLOURS.length], width: 1.5 }))],
      axes: [{ values: (u, splits) => splits.map((ts) => isoTime(ts).slice(11, 16)) }, { size: 50 }],
      legend: { live: true },
    }, data, $("#plot"));
    plotKey = key;
  } else {
    plot.setData(data);
  }
}

async function update() {
  try {
    const [sig, clock, devs, clients] = await Promise.all(
      ["signals", "clock", "devices", "clients"].map((p) => fetch(`/api/${p}`).then((r) => r.json())));
    renderClock(clock);
    renderSignals(sig);
    renderDevices(devs);
    renderClients(clients);
    await renderPlot();
    document.body.dataset.t = String(sig.t);
    document.body.dataset.devicesT = String(devs.t);
    $("#status").textContent = `updated ${new Date().toLocaleTimeString()}`;
    $("#status").classList.remove("stale");
  } catch (err) {
    $("#status").textContent = `no answer from the gateway (${err})`;
    $("#status").classList.add("stale");
  }
  setTimeout(update, PERIOD_MS);
}

async function setupFaults() {
  const f = await (await fetch("/api/faults")).json();
  $("#fault-kind").innerHTML = f.kinds.map((k) => `<option>${esc(k)}</option>`).join("");
  $("#faults-enabled").textContent = f.enabled ? "(needs the token given to --http-token)" : "(off: start with --http-token TOKEN)";
  $("#fault-form").addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const body = { device: $("#fault-device").value, kind: $("#fault-kind").value, point: $("#fault-point").value };
    if ($("#fault-delta").value) body.delta = +$("#fault-delta").value;
    const r = await fetch("/api/faults", { method: "POST", body: JSON.stringify(body),
      headers: { "Content-Type": "application/json", Authorization: `Bearer ${$("#fault-token").value}` } });
    const a = await r.json();
    $("#fault-result").textContent = r.ok ? `applied at t = ${a.t.toFixed(0)} s: ${a.applied.device} ${a.applied.kind}` : `${r.status}: ${a.error}`;
  });
}

$("#chips").addEventListener("click", (ev) => {
  const name = ev.target.dataset && ev.target.dataset.name;
  if (name) { chosen = chosen.filter((n) => n !== name); renderChips(); }
});
$("#signal-add").addEventListener("click", () => {
  const n = $("#signal-pick").value.trim();
  if (n && !chosen.includes(n)) { chosen.push(n); renderChips(); }
  $("#signal-pick").value = "";
});
renderChips();
setupFaults();
update();
