// EasyLab online mode: the model's drawing (/api/model) with the running
// program on it. The server polls the target for the items this page shows
// (/api/view: only what is visible in the diagram, and what the scope
// plots); the page reads the snapshots (/api/state) and draws them: active
// steps, step times, the transition each chart fired last, values on edges,
// vars, params and device data, the halt with its line in the model's
// text. Commands, breakpoints and writes go to the server as same-origin
// JSON with the page's CSRF header; so do
// forcing (a value held every instant, drawn on the diagram and listed
// until released) and conditional breakpoints (halt when ITEM OP VALUE).
"use strict";

(function () {
  const POLL_MS = 100;                  // the page asks the server (local) this often
  const MAX_POINTS = 20000;             // the scope's memory, per item
  const COLORS = ["#1565c0", "#c62828", "#2e7d32", "#6a1b9a", "#ef6c00", "#00838f", "#5d4037", "#37474f"];
  const SVG_NS = "http://www.w3.org/2000/svg";
  const $ = (id) => document.getElementById(id);

  const online = {                      // also the tests' window on the page
    model: null, items: new Map(), elements: {}, values: new Map(), lastSeq: -1, last: null, link: null,
    view: [], scope: { ids: [], times: [], series: new Map(), paused: false, plot: null },
    refreshes: [], breakpoints: [], forced: [],
  };
  window.easylabOnline = online;

  // ------------------------------------------------------------------ server calls

  async function api(path, body) {
    const init = { credentials: "same-origin", cache: "no-store" };
    if (body !== undefined) {
      init.method = "POST";
      init.headers = { "Content-Type": "application/json", [online.model.csrf_header]: online.model.csrf };
      init.body = JSON.stringify(body);
    }
    const response = await fetch(path, init);
    let data = null;
    try { data = await response.json(); } catch (_) { data = { error: `HTTP ${response.status}` }; }
    return { ok: response.ok, status: response.status, data };
  }

  function say(text, ok) {
    const m = $("msg");
    m.textContent = text;
    m.className = "msg " + (ok ? "ok" : "error");
  }

  // ------------------------------------------------------------------ values as text

  function formatValue(it, v) {
    if (v === undefined || v === null) return "?";
    if (Array.isArray(v)) {
      if (it.labels) return v.map((s) => it.labels[String(s)]).filter((n) => n).join(" + ") || "(none)";
      return "[" + v.map((x) => formatValue({ ...it, labels: null }, x)).join(", ") + "]";
    }
    if (it.labels) return it.labels[String(v)] || "(none)";
    if (it.type === "bool") return v ? "true" : "false";
    if (it.type === "float32") return typeof v === "number" ? String(Number(v.toPrecision(6))) : String(v);
    if (it.type === "time") return `${v} ms`;
    return String(v);
  }

  function numeric(v) {
    if (Array.isArray(v)) v = v[0];
    if (typeof v === "boolean") return v ? 1 : 0;
    return typeof v === "number" ? v : null;
  }

  // ------------------------------------------------------------------ the diagram

  function drawDiagram() {
    const doc = new DOMParser().parseFromString(online.model.svg, "image/svg+xml");
    const svg = document.importNode(doc.documentElement, true);
    $("diagram").replaceChildren(svg);
    for (const [id, info] of Object.entries(online.elements)) {
      const g = document.getElementById(id);
      if (!g) continue;
      info.g = g;
      if (info.point) g.setAttribute("data-point", info.point.join(","));
      else if (info.items.length) g.classList.add("has-items");
      if (info.items.length) {
        const kind = id.startsWith("step:") ? "step-time" : id.startsWith("transition:") ? "guard" : "";
        info.label = valueLabel(g, `el-value ${kind}`.trim());
      }
    }
    const box = svg.viewBox.baseVal;
    online.natural = [box.width, box.height];
    zoom(0);
    svg.addEventListener("click", onDiagramClick);
    $("diagram").addEventListener("scroll", scheduleView, { passive: true });
    window.addEventListener("resize", scheduleView);
  }

  // The drawing's scale: 0 fits it to the pane's width, else a factor of its natural size.
  function zoom(scale) {
    const svg = $("diagram").querySelector("svg");
    const [w, h] = online.natural;
    const fit = Math.max(0.1, ($("diagram").clientWidth - 4) / w);
    online.scale = scale === 0 ? fit : Math.min(4, Math.max(0.1, scale));
    svg.setAttribute("width", `${(w * online.scale).toFixed(0)}px`);
    svg.setAttribute("height", `${(h * online.scale).toFixed(0)}px`);
    scheduleView();
  }

  // A text element for an element's values: under a node, at the middle of an edge.
  function valueLabel(g, cls) {
    const t = document.createElementNS(SVG_NS, "text");
    t.setAttribute("class", cls);
    const path = g.querySelector("path");
    let x, y;
    if (g.classList.contains("edge") && path) {
      const p = path.getPointAtLength(path.getTotalLength() / 2);
      x = p.x + 3; y = p.y + 10;  // under the path: Graphviz puts its label above the middle
    } else {
      const b = g.getBBox();
      x = b.x + b.width / 2; y = b.y + b.height + 9;
      t.setAttribute("text-anchor", "middle");
    }
    t.setAttribute("x", x.toFixed(1));
    t.setAttribute("y", y.toFixed(1));
    g.appendChild(t);
    return t;
  }

  function onDiagramClick(event) {
    const g = event.target.closest("g[id]");
    const info = g && online.elements[g.id];
    if (!info) return;
    if (info.point) { toggleBreakpoint(g.id, info); return; }
    for (const id of info.items) addToScope(id);
    pick(info.items);
  }

  // An element's item becomes the one to force and to halt on (when the lists hold it).
  function pick(ids) {
    for (const list of ["force-item", "when-item"]) {
      const name = ids.map((id) => online.items.get(id).name)
        .find((n) => [...$(list).options].some((o) => o.value === n));
      if (name !== undefined) $(list).value = name;
    }
  }

  async function toggleBreakpoint(elementId, info) {
    const set = online.breakpoints.find((b) => b.element === elementId);
    const r = set ? await api("/api/breakpoint", { slot: set.slot })
      : await api("/api/breakpoint", { element: elementId });
    if (!r.ok) { say(r.data.error, false); return; }
    say(set ? `breakpoint ${set.slot} cleared (${set.at})` : `breakpoint ${r.data.slot} at ${r.data.at}`, true);
  }

  // ------------------------------------------------------------------ what is polled

  let viewTimer = null;
  function scheduleView() {
    if (viewTimer === null) viewTimer = setTimeout(() => { viewTimer = null; sendView(); }, 150);
  }

  // The items of the elements in sight, the charts of the steps in sight, what the scope plots.
  function visibleItems() {
    const pane = $("diagram").getBoundingClientRect();
    const ids = new Set(online.scope.ids);
    for (const info of Object.values(online.elements)) {
      if (!info.g) continue;
      const r = info.g.getBoundingClientRect();
      if (r.right < pane.left || r.left > pane.right || r.bottom < pane.top || r.top > pane.bottom) continue;
      for (const id of info.items) ids.add(id);
      if (info.chart_item !== undefined && info.chart_item !== null) ids.add(info.chart_item);
      if (info.fired_item !== undefined && info.fired_item !== null) ids.add(info.fired_item);
    }
    return [...ids].sort((a, b) => a - b);
  }

  async function sendView() {
    const ids = visibleItems();
    if (ids.join(",") === online.view.join(",")) return;
    const r = await api("/api/view", { items: ids });
    if (r.ok) online.view = r.data.items;
  }

  // ------------------------------------------------------------------ snapshots

  async function poll() {
    if (document.hidden) { setTimeout(poll, POLL_MS); return; }  // a hidden page asks nothing: the target rests
    try {
      const r = await api(`/api/state?after=${online.lastSeq}`);
      if (r.ok) {
        showLink(r.data.link);
        for (const s of r.data.snapshots) take(s);
        if (r.data.snapshots.length) show(r.data.snapshots[r.data.snapshots.length - 1]);
      }
    } catch (err) {
      showLink({ state: "offline", message: "the server does not answer" });
    }
    setTimeout(poll, POLL_MS);
  }

  function showLink(link) {
    online.link = link;
    $("link").className = "link " + link.state.replace(" ", "-");
    $("link-state").textContent = link.state;
    $("link-message").textContent = link.message;
    online.breakpoints = link.breakpoints || [];
    for (const info of Object.values(online.elements)) if (info.g) info.g.classList.remove("bp");
    const bpLines = new Set();
    for (const b of online.breakpoints) {
      const info = b.element && online.elements[b.element];
      if (info && info.g) info.g.classList.add("bp");
      const location = b.location || (info && info.location);  // a condition: its item's declaration
      if (location) bpLines.add(lineOf(location));
    }
    for (const line of document.querySelectorAll(".src-line")) {
      line.classList.toggle("bp-line", bpLines.has(Number(line.dataset.line)));
    }
    const listed = online.breakpoints.map((b) => `${b.slot}:${b.hits}`).join(" ");
    if (listed !== online.bpListed) {  // every breakpoint, those set elsewhere (the console) too
      online.bpListed = listed;
      $("bp-list").replaceChildren(...online.breakpoints.map((b) => {
        const button = document.createElement("button");
        button.type = "button";
        button.className = "secondary bp-chip";
        button.title = "clear this breakpoint";
        button.textContent = `${b.at} (hit ${b.hits}) ✕`;
        button.addEventListener("click", async () => {
          const r = await api("/api/breakpoint", { slot: b.slot });
          say(r.ok ? `breakpoint ${b.slot} cleared (${b.at})` : r.data.error, r.ok);
        });
        return button;
      }));
    }
    showForcing(link);
  }

  // What the firmware has no slots for (HELLO) replaces its control; the forced items are listed.
  function showForcing(link) {
    const none = link.state === "connected" ? link.no_slots || {} : {};
    for (const [key, form] of [["force", "force-form"], ["conditions", "when-form"]]) {
      const why = none[key];
      $(form).hidden = why !== undefined;
      const note = $(key === "force" ? "force-none" : "when-none");
      note.hidden = why === undefined;
      note.textContent = why || "";
    }
    online.forced = link.forced || [];
    const listed = online.forced.map((f) => `${f.name}=${f.shown}`).join(" ");
    if (listed === online.forcedListed) return;
    online.forcedListed = listed;
    $("forced-list").replaceChildren(...online.forced.map((f) => {
      const button = document.createElement("button");
      button.type = "button";
      button.className = "secondary forced-chip";
      button.title = "release it";
      button.textContent = `${f.name} = ${f.shown} (forced) ✕`;
      button.addEventListener("click", async () => {
        const r = await api("/api/release", { name: online.items.get(f.item).name, element: f.element });
        say(r.ok ? `released ${f.name}` : r.data.error, r.ok);
      });
      return button;
    }));
    markScopeForced();
    if (online.last) show(online.last);
  }

  // A plotted item that is forced says so in the scope's list (its values there are the forced ones).
  function markScopeForced() {
    for (const b of $("scope-list").querySelectorAll("button[data-item]")) {
      const id = Number(b.dataset.item);
      const forced = online.forced.some((f) => f.item === id);
      b.classList.toggle("forced-chip", forced);
      b.textContent = `${online.items.get(id).name}${forced ? " (forced)" : ""} ✕`;
    }
  }

  function take(s) {
    online.lastSeq = s.seq;
    for (const [id, v] of Object.entries(s.values)) online.values.set(Number(id), v);
    online.refreshes.push([performance.now(), s.wire_bytes]);
    if (online.refreshes.length > 50) online.refreshes.shift();
    record(s);
  }

  function lineOf(location) {
    const m = /:(\d+)$/.exec(location || "");
    return m ? Number(m[1]) : null;
  }

  function show(s) {
    online.last = s;
    const state = $("run-state");
    state.textContent = s.halted ? `halted (${s.why})` : "running";
    state.className = "chip " + (s.halted ? "halted" : "running");
    $("halt-at").textContent = s.halted ? `at ${s.at || "?"}` + (s.location ? ` (${s.location})` : "") : "";
    const ms = s.ms === null ? "" : `${s.ms} ms, `;
    $("clock").textContent = `${ms}tick ${s.tick}`;
    const statusItems = [...online.items.values()].filter((it) => it.kind === "status");
    const overruns = statusItems.map((it) => `${it.name} ${formatValue(it, online.values.get(it.id))}`);
    const rs = online.refreshes;
    const rate = rs.length > 1 ? (rs.length - 1) * 1000 / (rs[rs.length - 1][0] - rs[0][0]) : 0;
    $("counts").textContent = [`${rate.toFixed(1)} refreshes/s`, `${s.wire_bytes} bytes/refresh`,
      `${Object.keys(s.values).length} items`, `snapshot: ${s.consistency}`, ...overruns].join(" · ");
    // the diagram
    for (const [id, info] of Object.entries(online.elements)) {
      if (!info.g) continue;
      if (info.chart_item !== undefined && info.chart_item !== null) {
        const active = online.values.get(info.chart_item);
        const steps = Array.isArray(active) ? active : [active];
        info.g.classList.toggle("active", steps.includes(info.step));
      }
      if (info.transition !== undefined && info.fired_item !== undefined && info.fired_item !== null) {
        info.g.classList.toggle("fired", online.values.get(info.fired_item) === info.transition);
      }
      info.g.classList.toggle("halted-here", s.halted && s.element === id);
      if (info.label && id.startsWith("transition:")) {  // the guard, on this snapshot's values
        const holds = s.guards[id];
        info.label.textContent = holds === undefined ? "" : (holds ? "✓ true" : "✗ false");
        info.label.classList.toggle("holds", holds === true);
      } else if (info.label) {
        const forced = new Map(online.forced.filter((f) => info.items.includes(f.item)).map((f) => [f.item, f]));
        info.g.classList.toggle("forced", forced.size > 0);
        info.label.classList.toggle("forced", forced.size > 0);
        const shown = info.items.filter((i) => online.values.has(i) || forced.has(i));
        info.label.textContent = shown.map((i) => {
          const it = online.items.get(i);
          const v = forced.has(i) ? `${forced.get(i).shown} (forced)` : formatValue(it, online.values.get(i));
          return id.startsWith("step:") ? `t = ${v}` : (info.items.length > 1 ? `${shortName(it.name)}=${v}` : `= ${v}`);
        }).join("  ");
        info.label.classList.toggle("stale", !info.items.every((i) => i in s.values || String(i) in s.values));
      }
    }
    // the model's text
    const line = s.halted ? lineOf(s.location) : null;
    const file = s.location ? s.location.replace(/:\d+$/, "") : null;
    const here = line !== null && (file === online.model.location_file || online.model.location_file === null);
    const previous = document.querySelector(".src-line.halted-line");
    const target = here ? document.querySelector(`.src-line[data-line="${line}"]`) : null;
    if (previous !== target) {
      if (previous) previous.classList.remove("halted-line");
      if (target) {  // scrolled into the middle of the text's pane (the page itself stays)
        target.classList.add("halted-line");
        const pane = $("source");
        pane.scrollTop = target.offsetTop - pane.clientHeight / 2;
      }
    }
  }

  function shortName(name) { return name.split(".").pop(); }

  // ------------------------------------------------------------------ the scope

  function record(s) {
    const sc = online.scope;
    if (!sc.ids.length || s.ms === null) return;
    const n = sc.times.length;
    if (n && s.ms < sc.times[n - 1]) clearScope();  // the target was reset: a new time line
    if (sc.times.length && s.ms === sc.times[sc.times.length - 1]) return;  // the same instant again (halted)
    sc.times.push(s.ms);
    for (const id of sc.ids) {
      const v = id in s.values ? s.values[id] : s.values[String(id)];
      sc.series.get(id).push(v === undefined ? null : numeric(v));
    }
    if (sc.times.length > MAX_POINTS) {
      sc.times.shift();
      for (const data of sc.series.values()) data.shift();
    }
    if (!sc.paused) drawScope();
  }

  function drawScope() {
    const sc = online.scope;
    if (typeof uPlot === "undefined" || !sc.ids.length || sc.times.length < 2) return;  // no range to draw yet
    const data = [sc.times, ...sc.ids.map((id) => sc.series.get(id))];
    if (!sc.plot) {
      const holder = $("scope");
      holder.replaceChildren();
      const opts = {
        width: Math.max(300, holder.clientWidth - 4), height: 220, scales: { x: { time: false } },
        axes: [{ label: "ms" }, {}], cursor: { drag: { x: true, y: false } },
        series: [{ label: "ms" }, ...sc.ids.map((id, k) => {
          const it = online.items.get(id);
          const series = { label: it.name, stroke: COLORS[k % COLORS.length], width: 1.5 };
          const stepwise = it.type === "bool" || it.kind === "chart" || it.kind === "fired";
          if (stepwise) series.paths = uPlot.paths.stepped({ align: 1 });
          return series;
        })],
      };
      sc.plot = new uPlot(opts, data, holder);
      return;
    }
    sc.plot.setData(data, true);
    const w = Number($("scope-window").value);
    const last = sc.times[sc.times.length - 1];
    const first = Math.max(sc.times[0], last - w);
    if (w > 0 && last > first) sc.plot.setScale("x", { min: first, max: last });
  }

  function addToScope(id) {
    const sc = online.scope;
    const it = online.items.get(id);
    if (!it || sc.ids.includes(id) || it.type === undefined) return;
    sc.ids.push(id);
    sc.series.set(id, sc.times.map(() => null));
    rebuildScope();
    sendView();
  }

  function removeFromScope(id) {
    const sc = online.scope;
    sc.ids = sc.ids.filter((x) => x !== id);
    sc.series.delete(id);
    rebuildScope();
    sendView();
  }

  function clearScope() {
    const sc = online.scope;
    sc.times = [];
    for (const id of sc.ids) sc.series.set(id, []);
    rebuildScope();
  }

  function rebuildScope() {
    const sc = online.scope;
    if (sc.plot) { sc.plot.destroy(); sc.plot = null; }
    const list = $("scope-list");
    list.replaceChildren(...sc.ids.map((id, k) => {
      const b = document.createElement("button");
      b.type = "button";
      b.className = "secondary";
      b.dataset.item = String(id);
      b.style.borderLeft = `4px solid ${COLORS[k % COLORS.length]}`;
      b.addEventListener("click", () => removeFromScope(id));
      return b;
    }));
    markScopeForced();
    if (!sc.ids.length) $("scope").replaceChildren();
    drawScope();
  }

  // What the scope recorded as CSV: `ms` then one column per item, empty where no value was read.
  function csvText() {
    const sc = online.scope;
    return [["ms", ...sc.ids.map((id) => online.items.get(id).name)].join(","),
      ...sc.times.map((t, k) => [t, ...sc.ids.map((id) => sc.series.get(id)[k] ?? "")].join(","))].join("\n") + "\n";
  }

  const WIDTHS = { bool: 1, int8: 8, uint8: 8, int16: 16, uint16: 16, int32: 32, uint32: 32, time: 32 };

  // The same as VCD, as the host board's traces write it (boards/host/host_trace.c): `$timescale 1us`,
  // bool a 1-bit wire, integers wires of their width (two's complement), time a 32-bit wire of ms,
  // float32 `real`, a chart's state a wire of one bit per step (bit i: step i active), its last fired
  // transition a wire of its width (the transition's id, all ones: none).
  function vcdText() {
    const sc = online.scope;
    const name = (text) => text.replace(/[^A-Za-z0-9_.]/g, "_");
    const signals = sc.ids.map((id, k) => {
      const it = online.items.get(id);
      const oneHot = it.kind === "chart";  // a chart's state; its last fired transition is a number
      const steps = oneHot ? Object.keys(it.labels).filter((key) => it.labels[key] !== null).length : 0;
      const code = k < 94 ? String.fromCharCode(33 + k) : String.fromCharCode(33 + (k % 94), 33 + Math.floor(k / 94));
      const real = it.type === "float32";
      return { id, it, code, real, oneHot, width: real ? 64 : (oneHot ? Math.max(steps, 1) : WIDTHS[it.type] || 32) };
    });
    const value = (sig, v) => {
      if (sig.real) return `r${v} ${sig.code}`;
      if (sig.width === 1 && !sig.oneHot) return `${v ? 1 : 0}${sig.code}`;
      let bits;
      if (sig.oneHot) bits = [...Array(sig.width)].map((_, i) => (sig.width - 1 - i === v ? "1" : "0")).join("");
      else bits = (((v % 2 ** sig.width) + 2 ** sig.width) % 2 ** sig.width).toString(2).padStart(sig.width, "0");
      return `b${bits} ${sig.code}`;
    };
    const lines = [`$comment EasyLab online mode: the scope of ${online.model.model} $end`, "$timescale 1us $end",
      `$scope module ${name(online.model.model)} $end`,
      ...signals.map((sig) => `$var ${sig.real ? "real" : "wire"} ${sig.width} ${sig.code} ${name(sig.it.name)} $end`),
      "$upscope $end", "$enddefinitions $end"];
    const shown = [];
    sc.times.forEach((t, k) => {
      const changes = [];
      signals.forEach((sig, j) => {
        const v = sc.series.get(sig.id)[k];
        if (v === null || v === undefined) return;
        const text = value(sig, v);
        if (text !== shown[j]) { changes.push(text); shown[j] = text; }
      });
      const at = `#${Math.round(t * 1000)}`;
      if (k === 0) lines.push(at, "$dumpvars", ...changes, "$end");
      else if (changes.length) lines.push(at, ...changes);
    });
    if (sc.times.length) lines.push(`#${Math.round(sc.times[sc.times.length - 1] * 1000) + 1}`);
    return lines.join("\n") + "\n";
  }

  function download(text, type, suffix) {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([text], { type }));
    a.download = `${online.model.model}-scope.${suffix}`;
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 1000);
  }
  online.csv = csvText;  // for the tests
  online.vcd = vcdText;

  // ------------------------------------------------------------------ controls

  async function command(body) {
    const r = await api("/api/command", body);
    if (r.ok) say(`${body.command}${body.unit ? " " + body.unit : ""}: done`, true);
    else say(r.data.error, false);
  }

  function setUpControls() {
    $("run").addEventListener("click", () => command({ command: "run" }));
    $("break").addEventListener("click", () => command({ command: "break" }));
    $("reset").addEventListener("click", () => { clearScope(); command({ command: "reset" }); });
    for (const b of document.querySelectorAll("button.step")) {
      b.addEventListener("click", () => command({ command: "step", unit: b.dataset.unit }));
    }
    $("zoom-fit").addEventListener("click", () => zoom(0));
    $("zoom-in").addEventListener("click", () => zoom(online.scale * 1.25));
    $("zoom-out").addEventListener("click", () => zoom(online.scale / 1.25));
    $("clear-bps").addEventListener("click", async () => {
      const r = await api("/api/breakpoint", { slot: "all" });
      say(r.ok ? "every breakpoint cleared" : r.data.error, r.ok);
    });
    const writable = online.model.items.filter((it) => it.writable);
    $("write-item").replaceChildren(...writable.map((it) => new Option(it.name, it.name)));
    $("write-form").addEventListener("submit", async (event) => {
      event.preventDefault();
      const name = $("write-item").value;
      const r = await api("/api/write", { name, value: $("write-value").value });
      say(r.ok ? `${name} := ${r.data.value} (${r.data.applied ? "applied" : "at the next instant"})`
        : r.data.error, r.ok);
    });
    $("force-item").replaceChildren(...writable.map((it) => new Option(it.name, it.name)));
    $("force-form").addEventListener("submit", async (event) => {
      event.preventDefault();
      const name = $("force-item").value;
      const r = await api("/api/force", { name, value: $("force-value").value });
      say(r.ok ? `${name} forced to ${r.data.shown} (${r.data.applied ? "from now" : "from the next instant"}, `
        + "every instant until released)" : r.data.error, r.ok);
    });
    $("release-all").addEventListener("click", async () => {
      const r = await api("/api/release", { name: "all" });
      say(r.ok ? "released every forced item" : r.data.error, r.ok);
    });
    const comparable = online.model.items.filter((it) => it.kind !== "status");
    $("when-item").replaceChildren(...comparable.map((it) => new Option(it.name, it.name)));
    $("when-form").addEventListener("submit", async (event) => {
      event.preventDefault();
      const when = { name: $("when-item").value, op: $("when-op").value, value: $("when-value").value };
      const r = await api("/api/breakpoint", { when });
      say(r.ok ? `breakpoint ${r.data.slot} ${r.data.at}` : r.data.error, r.ok);
    });
    const plottable = comparable;
    $("scope-item").replaceChildren(...plottable.map((it) => new Option(it.name, String(it.id))));
    $("scope-add").addEventListener("click", () => addToScope(Number($("scope-item").value)));
    $("scope-pause").addEventListener("click", () => {
      const sc = online.scope;
      sc.paused = !sc.paused;
      $("scope-pause").setAttribute("aria-pressed", String(sc.paused));
      $("scope-pause").textContent = sc.paused ? "Resume" : "Pause";
      if (!sc.paused) drawScope();
    });
    $("scope-window").addEventListener("change", drawScope);
    $("scope-csv").addEventListener("click", () => download(csvText(), "text/csv", "csv"));
    $("scope-vcd").addEventListener("click", () => download(vcdText(), "text/plain", "vcd"));
    $("scope-clear").addEventListener("click", clearScope);
  }

  function showSource() {
    const lines = online.model.source.split("\n");
    $("source-name").textContent = online.model.file;
    $("source").replaceChildren(...lines.map((text, k) => {
      const div = document.createElement("div");
      div.className = "src-line";
      div.dataset.line = String(k + 1);
      const ln = document.createElement("span");
      ln.className = "ln";
      ln.textContent = String(k + 1);
      div.append(ln, text);
      return div;
    }));
  }

  async function start() {
    const r = await api("/api/model");
    if (!r.ok) { say(r.data.error, false); return; }
    online.model = r.data;
    online.elements = r.data.elements;
    for (const it of r.data.items) online.items.set(it.id, it);
    $("model").textContent = r.data.model;
    $("title").textContent = r.data.title || "";
    $("program").textContent = `program ${r.data.program_id}`;
    document.title = `${r.data.model}: EasyLab online`;
    showSource();
    drawDiagram();
    setUpControls();
    await sendView();
    poll();
  }

  start();
})();
