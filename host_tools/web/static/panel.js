// EasyLab service panel: the page is built from the service map (/api/map);
// the values come from the server's samples of the device (/api/samples),
// fetched once per sampling period. Writes, backups and restores go to the
// server as same-origin JSON with the panel's CSRF header.
"use strict";

(function () {
  const MAX_POINTS = 2400;              // per plotted item: 10 min at 250 ms
  const TIME_UNITS = { ms: 1, s: 1000, min: 60000, m: 60000, h: 3600000 };
  const TYPE_LIMITS = {
    int8: [-128, 127], uint8: [0, 255], int16: [-32768, 32767], uint16: [0, 65535],
    int32: [-2147483648, 2147483647], uint32: [0, 4294967295], time: [0, 4294967295],
  };
  const GROUPS = [                      // [title, kind, access]
    ["Measurements", "var", "ro"], ["Parameters", "param", "rw"],
    ["Commands", "var", "rw"], ["Fixed parameters", "param", "ro"],
  ];
  const COLORS = ["#1565c0", "#00838f", "#6a1b9a", "#ef6c00", "#2e7d32", "#c62828"];
  const EXCEPTION_CODE = (code) => String(code).padStart(2, "0");

  const $ = (id) => document.getElementById(id);
  const panel = {                        // also the tests' window on the page
    map: null, items: [], rows: new Map(), plots: new Map(),
    times: [], series: [], lastSeq: -1, link: null, serverOk: null, send: null,
  };
  window.easylabPanel = panel;

  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") e.className = v;
      else if (k === "text") e.textContent = v;
      else e.setAttribute(k, v);
    }
    for (const c of children) if (c !== null && c !== undefined) e.append(c);
    return e;
  }

  // ------------------------------------------------------------------ server calls

  async function api(path, body) {
    const init = { credentials: "same-origin", cache: "no-store" };
    if (body !== undefined) {
      init.method = "POST";
      init.headers = { "Content-Type": "application/json", [panel.map.csrf_header]: panel.map.csrf };
      init.body = JSON.stringify(body);
    }
    const response = await fetch(path, init);
    let data = null;
    try { data = await response.json(); } catch (_) { data = { error: `HTTP ${response.status}` }; }
    return { ok: response.ok, status: response.status, data };
  }

  // A refusal in words: the device's Modbus exception first, when there is one.
  function refusalText(data) {
    if (data && data.exception !== undefined) {
      return `Refused by the device: ${data.words} (exception ${EXCEPTION_CODE(data.exception)})`;
    }
    return (data && data.error) || "refused";
  }

  function showMsg(node, ok, text, detail) {
    node.className = "msg " + (ok ? "ok" : "error");
    node.textContent = text;
    if (detail) node.append(el("span", { class: "detail", text: detail }));
  }

  // ------------------------------------------------------------------ values

  function format(it, v) {
    if (v === null || v === undefined) return "–";
    if (typeof v === "string") return v;                      // NaN, Infinity
    if (it.type === "bool") return v ? "on" : "off";
    if (it.type === "float32") return String(Number(v.toPrecision(7)));
    return String(v);
  }

  function rangeText(it) {
    return it.range ? `range ${format(it, it.range[0])}..${format(it, it.range[1])}` : "";
  }

  // The value a text stands for, or null when the server had better judge it.
  function numberOf(it, text) {
    const t = text.trim();
    if (it.type === "float32") return t === "" || Number.isNaN(Number(t)) ? null : Number(t);
    if (it.type === "time") {
      const m = /^(\d+(?:\.\d+)?)\s*(ms|s|min|m|h)?$/.exec(t);
      return m ? parseFloat(m[1]) * TIME_UNITS[m[2] || "ms"] : null;
    }
    return /^[+-]?(0x[0-9a-f]+|\d+)$/i.test(t) ? parseInt(t, t.toLowerCase().includes("0x") ? 16 : 10) : null;
  }

  // The range check before sending: a message when the value is refused here.
  function checkRange(it, text) {
    if (it.type === "bool") return null;
    if (text.trim() === "") return "give a value";
    const v = numberOf(it, text);
    if (v === null) return null;
    const [lo, hi] = it.range || TYPE_LIMITS[it.type] || [-Infinity, Infinity];
    if (v < lo || v > hi) {
      const unit = it.unit ? " " + it.unit : "";
      return `${text.trim()} is outside the range of ${it.name} (${format(it, lo)}..${format(it, hi)}${unit}): not sent`;
    }
    return null;
  }

  // ------------------------------------------------------------------ items

  function itemRow(it, index) {
    const value = el("span", { class: "value", text: "–" });
    const plotButton = el("button", { type: "button", class: "plot-toggle", "aria-pressed": "false", text: "Plot" });
    const row = el("div", { class: "item stale", "data-item": it.name },
      el("div", { class: "head" }, el("span", { class: "name", text: it.name }),
        it.persist ? el("span", { class: "badge", title: "kept across resets", text: "persist" }) : null,
        it.access === "ro" ? el("span", { class: "badge", title: "read-only", text: "ro" }) : null, plotButton),
      el("div", { class: "reading" }, value, " ", el("span", { class: "unit", text: it.unit || "" })),
      el("div", { class: "meta", text: [it.type, rangeText(it)].filter(Boolean).join(" · ") }));
    const entry = { it, index, row, value, plotButton, msg: null };
    if (it.access === "rw") {
      const input = it.type === "bool"
        ? el("select", { name: "value", "aria-label": `new value of ${it.name}` },
          el("option", { value: "1", text: "on" }), el("option", { value: "0", text: "off" }))
        : el("input", { name: "value", type: "text", inputmode: it.type === "float32" ? "decimal" : "numeric",
          autocomplete: "off", "aria-label": `new value of ${it.name}`,
          placeholder: it.range ? `${format(it, it.range[0])}..${format(it, it.range[1])}` : it.type });
      const form = el("form", { class: "edit" }, input, el("button", { type: "submit", class: "set", text: "Set" }));
      entry.msg = el("div", { class: "msg", role: "status" });
      row.append(form, entry.msg);
      form.addEventListener("submit", (ev) => { ev.preventDefault(); submitEdit(entry, input); });
      input.addEventListener("input", () => input.classList.remove("invalid"));
    }
    plotButton.addEventListener("click", () => togglePlot(entry));
    return entry;
  }

  function buildPage(map) {
    document.title = `${map.model} · EasyLab service panel`;
    $("model").textContent = map.model;
    $("title").textContent = map.title || "";
    $("program").textContent = `program ${map.program_id} · device ${map.where}`;
    const groups = $("groups");
    map.items.forEach((it, index) => panel.rows.set(it.name, itemRow(it, index)));
    for (const [title, kind, access] of GROUPS) {
      const entries = [...panel.rows.values()].filter((e) => e.it.kind === kind && e.it.access === access);
      if (!entries.length) continue;
      const section = el("section", { class: "group", "data-group": `${kind}-${access}` }, el("h2", { text: title }),
        el("div", { class: "items" }, ...entries.map((e) => e.row)));
      groups.append(section);
    }
    panel.series = map.items.map(() => []);
  }

  async function submitEdit(entry, input) {
    const text = input.value;
    const refused = checkRange(entry.it, text);
    if (refused) {
      input.classList.add("invalid");
      showMsg(entry.msg, false, refused);
      return;
    }
    await send(entry.it.name, text);
  }

  // Send a value (after the page's own checks, or without them: the device judges).
  async function send(name, text) {
    const entry = panel.rows.get(name);
    if (!entry || !entry.msg) return false;            // not a writable item of this map
    showMsg(entry.msg, true, "sending…");
    let r;
    try {
      r = await api("/api/write", { name, value: text });
    } catch (err) {
      showMsg(entry.msg, false, "the panel server does not answer; nothing was sent");
      return false;
    }
    if (!r.ok) {
      showMsg(entry.msg, false, refusalText(r.data), r.data && r.data.exception !== undefined ? r.data.error : "");
      return false;
    }
    entry.value.textContent = format(entry.it, r.data.value);
    entry.writtenAfter = r.data.seq;  // samples up to this one were read before the write
    showMsg(entry.msg, true, `set: ${entry.it.name} = ${format(entry.it, r.data.value)}${entry.it.unit ? " " + entry.it.unit : ""}`);
    return true;
  }
  panel.send = send;

  // ------------------------------------------------------------------ plots

  function storageKey() { return `easylab-panel:${panel.map.model}:plots`; }

  function savePlots() {
    try { localStorage.setItem(storageKey(), JSON.stringify([...panel.plots.keys()])); } catch (_) { /* private mode */ }
  }

  function chosenPlots() {
    try {
      const saved = JSON.parse(localStorage.getItem(storageKey()) || "null");
      if (Array.isArray(saved)) return saved.filter((n) => panel.rows.has(n));
    } catch (_) { /* none saved */ }
    const first = panel.map.items.find((it) => it.kind === "var" && it.access === "ro" && it.type !== "bool");
    return first ? [first.name] : [];
  }

  function plotWidth(holder) { return Math.max(200, holder.clientWidth); }

  function togglePlot(entry) {
    if (panel.plots.has(entry.it.name)) removePlot(entry); else addPlot(entry);
    savePlots();
  }

  function addPlot(entry) {
    const it = entry.it;
    const color = COLORS[panel.plots.size % COLORS.length];
    const holder = el("div", { class: "holder" });
    const last = el("span", { class: "last" });
    const close = el("button", { type: "button", class: "secondary", "aria-label": `stop plotting ${it.name}`, text: "×" });
    const card = el("div", { class: "plot", "data-plot": it.name },
      el("div", { class: "plot-head" }, el("span", { text: it.name + (it.unit ? ` [${it.unit}]` : "") }), last, close),
      holder);
    $("plot-list").append(card);
    $("plots-hint").hidden = true;
    const series = { label: it.name, stroke: color, width: 2, points: { show: false } };
    if (it.type === "bool") series.paths = uPlot.paths.stepped({ align: 1 });
    const opts = {
      width: plotWidth(holder), height: 190, legend: { show: false }, cursor: { drag: { x: false, y: false } },
      scales: { x: { time: true } }, series: [{}, series],
      axes: [{ stroke: "#5d6a74" }, { stroke: "#5d6a74", size: 56 }],
    };
    const plot = new uPlot(opts, [panel.times, panel.series[entry.index]], holder);
    panel.plots.set(it.name, { plot, card, holder, last, entry });
    close.addEventListener("click", () => { removePlot(entry); savePlots(); });
    entry.plotButton.setAttribute("aria-pressed", "true");
    entry.plotButton.textContent = "Plotted";
  }

  function removePlot(entry) {
    const p = panel.plots.get(entry.it.name);
    if (!p) return;
    p.plot.destroy();
    p.card.remove();
    panel.plots.delete(entry.it.name);
    entry.plotButton.setAttribute("aria-pressed", "false");
    entry.plotButton.textContent = "Plot";
    $("plots-hint").hidden = panel.plots.size > 0;
  }

  function redrawPlots() {
    for (const p of panel.plots.values()) {
      p.plot.setData([panel.times, panel.series[p.entry.index]]);
      const n = panel.times.length;
      p.last.textContent = n ? format(p.entry.it, panel.series[p.entry.index][n - 1]) : "";
    }
  }

  window.addEventListener("resize", () => {
    for (const p of panel.plots.values()) p.plot.setSize({ width: plotWidth(p.holder), height: 190 });
  });

  // ------------------------------------------------------------------ samples and the link

  function addSamples(samples) {
    for (const s of samples) {
      panel.times.push(s.t);
      s.v.forEach((v, k) => panel.series[k].push(typeof v === "boolean" ? (v ? 1 : 0) : (typeof v === "number" ? v : null)));
      panel.lastSeq = s.seq;
    }
    const extra = panel.times.length - MAX_POINTS;
    if (extra > 0) {
      panel.times.splice(0, extra);
      for (const column of panel.series) column.splice(0, extra);
    }
    const latest = samples[samples.length - 1];
    if (latest) {
      for (const entry of panel.rows.values()) {
        // A sample taken before the item's last write would show the old value again.
        if (entry.writtenAfter !== undefined && latest.seq <= entry.writtenAfter) continue;
        entry.value.textContent = format(entry.it, latest.v[entry.index]);
      }
      panel.lastTime = latest.t;
    }
    if (samples.length) redrawPlots();
  }

  function showLink(link, now) {
    panel.link = link;
    const stale = link.state !== "connected" || !panel.lastTime || now - panel.lastTime > Math.max(2, 4 * link.period);
    $("link").className = "link " + link.state;
    $("link-state").textContent = { connected: "connected", connecting: "connecting", lost: "device lost" }[link.state];
    $("link-message").textContent = link.message;
    const s = link.stats;
    $("link-counts").textContent = `${s.requests} requests · ${s.timeouts} timeouts · ${s.exceptions} exceptions · ` +
      `${s.lost} connections lost · ${link.connects} connects`;
    for (const entry of panel.rows.values()) entry.row.classList.toggle("stale", stale);
    const banner = $("banner");
    if (link.state === "connected") {
      banner.hidden = true;
    } else {
      banner.hidden = false;
      banner.className = "banner " + link.state;
      banner.textContent = link.state === "lost"
        ? `The device at ${link.where} went away: ${link.message}. The panel reconnects by itself; the values shown are the last ones read.`
        : `Waiting for the device at ${link.where}: ${link.message}.`;
    }
  }

  function showServerDown(err) {
    panel.serverOk = false;
    $("link").className = "link offline";
    $("link-state").textContent = "panel offline";
    $("link-message").textContent = "";
    const banner = $("banner");
    banner.hidden = false;
    banner.className = "banner";
    banner.textContent = `The panel server does not answer (${err}); trying again.`;
    for (const entry of panel.rows.values()) entry.row.classList.add("stale");
  }

  async function poll() {
    try {
      const r = await api(`/api/samples?after=${panel.lastSeq}`);
      if (!r.ok) throw new Error(r.data.error || `HTTP ${r.status}`);
      panel.serverOk = true;
      addSamples(r.data.samples);
      showLink(r.data.link, r.data.now);
    } catch (err) {
      showServerDown(err.message || err);
    }
    setTimeout(poll, Math.max(200, 1000 * panel.map.period));
  }

  // ------------------------------------------------------------------ backup and restore

  async function downloadBackup() {
    const msg = $("backup-msg");
    showMsg(msg, true, "reading the params…");
    let response;
    try {
      response = await fetch("/api/backup", { credentials: "same-origin", cache: "no-store" });
    } catch (err) {
      showMsg(msg, false, "the panel server does not answer");
      return;
    }
    if (!response.ok) {
      let data = null;
      try { data = await response.json(); } catch (_) { /* not JSON */ }
      showMsg(msg, false, "no backup: " + refusalText(data));
      return;
    }
    const text = await response.text();
    const name = (/filename="([^"]+)"/.exec(response.headers.get("Content-Disposition") || "") || [])[1]
      || `${panel.map.model}-params.json`;
    const url = URL.createObjectURL(new Blob([text], { type: "application/json" }));
    const a = el("a", { href: url, download: name });
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
    const count = Object.keys(JSON.parse(text).params).length;
    showMsg(msg, true, `backup of ${count} params saved as ${name}`);
  }

  let pendingRestore = null;

  async function chooseRestore(file) {
    const msg = $("backup-msg");
    pendingRestore = null;
    $("restore-confirm").hidden = true;
    if (!file) return;
    let doc;
    try {
      doc = JSON.parse(await file.text());
    } catch (_) {
      showMsg(msg, false, `${file.name} is not a backup (not JSON)`);
      return;
    }
    if (!doc || typeof doc.params !== "object" || doc.params === null) {
      showMsg(msg, false, `${file.name} is not a backup made by easylab-service`);
      return;
    }
    pendingRestore = doc;
    const n = Object.keys(doc.params).length;
    $("restore-what").textContent = `Write ${n} params of model ${doc.model} from ${file.name} to the device?`;
    $("restore-confirm").hidden = false;
    showMsg(msg, true, "");
  }

  async function restore() {
    const msg = $("backup-msg");
    const doc = pendingRestore;
    $("restore-confirm").hidden = true;
    $("restore-file").value = "";
    if (!doc) return;
    pendingRestore = null;
    showMsg(msg, true, "restoring…");
    let r;
    try {
      r = await api("/api/restore", doc);
    } catch (_) {
      showMsg(msg, false, "the panel server does not answer; nothing was restored");
      return;
    }
    if (!r.ok) {
      showMsg(msg, false, "not restored: " + refusalText(r.data));
      return;
    }
    const d = r.data;
    const notes = [...d.skipped, ...d.refused.map((x) => `${x.name}: ${x.error}`)].join("\n");
    showMsg(msg, d.refused.length === 0, `restored ${d.restored} of ${d.total} params`, notes);
  }

  // ------------------------------------------------------------------ start

  async function start() {
    let r;
    try {
      r = await api("/api/map");
    } catch (err) {
      showServerDown(err.message || err);
      setTimeout(start, 2000);
      return;
    }
    if (!r.ok) {
      showServerDown(r.data.error);
      return;
    }
    panel.map = r.data;
    panel.items = r.data.items;
    buildPage(r.data);
    for (const name of chosenPlots()) addPlot(panel.rows.get(name));
    $("backup-button").addEventListener("click", downloadBackup);
    $("restore-file").addEventListener("change", (ev) => chooseRestore(ev.target.files[0]));
    $("restore-go").addEventListener("click", restore);
    $("restore-cancel").addEventListener("click", () => {
      pendingRestore = null;
      $("restore-confirm").hidden = true;
      $("restore-file").value = "";
    });
    poll();
  }

  start();
})();
