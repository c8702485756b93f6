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
    ["Commands", "var", "rw"], ["Fixed parameters", "param", "ro"], ["Link faults", "status", "ro"],
  ];
  const COLORS = ["#1565c0", "#00838f", "#6a1b9a", "#ef6c00", "#2e7d32", "#5d4037"];
  const ALARM_COLOR = "#c62828";
  const PLOT_HEIGHT = 200;
  // A decimal number as typed (host_tools/units.py's rule): no hex, an exponent of at most 3 digits.
  const DECIMAL = /^([+-]?)(\d+\.?\d*|\.\d+)(?:[eE]([+-]?\d{1,3}))?$/;
  const EXCEPTION_CODE = (code) => String(code).padStart(2, "0");

  const $ = (id) => document.getElementById(id);
  const panel = {                        // also the tests' window on the page
    map: null, items: [], rows: new Map(), charts: [], marks: [], paused: false,
    times: [], series: [], raw: [], lastSeq: -1, link: null, serverOk: null, send: null,
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
    delete node.dataset.link;
    if (detail) node.append(el("span", { class: "detail", text: detail }));
  }

  // A message about the connection (the device or the panel server away):
  // cleared when the connection is back (clearLinkMsgs).
  function showLinkMsg(node, text) {
    showMsg(node, false, text);
    node.dataset.link = "1";
  }

  function clearLinkMsgs() {
    for (const node of document.querySelectorAll('.msg[data-link="1"]')) {
      node.className = "msg";
      node.textContent = "";
      delete node.dataset.link;
    }
  }

  // 503: the device is away; anything else is the request's own refusal.
  function showRefusal(node, r, prefix) {
    const text = prefix + refusalText(r.data);
    if (r.status === 503) showLinkMsg(node, text);
    else showMsg(node, false, text, r.data && r.data.exception !== undefined ? r.data.error : "");
  }

  // ------------------------------------------------------------------ values

  // An item's scale as BigInt digits and decimals ("0.1": 1n and 1): engineering
  // value = stored value x scale, computed exactly as host_tools/units.py does.
  function scaleOf(it) {
    if (!it._scale) {
      const [whole, frac = ""] = String(it.scale || "1").split(".");
      it._scale = { digits: BigInt(whole + frac), decimals: frac.length, one: (it.scale || "1") === "1" };
    }
    return it._scale;
  }

  function scaledText(it, stored) {
    const s = scaleOf(it);
    let n = BigInt(stored) * s.digits;
    if (!s.decimals) return n.toString();
    const negative = n < 0n;
    if (negative) n = -n;
    const digits = n.toString().padStart(s.decimals + 1, "0");
    return (negative ? "-" : "") + digits.slice(0, -s.decimals) + "." + digits.slice(-s.decimals);
  }

  function isScaled(it) { return it.type in TYPE_LIMITS && it.type !== "time" && !scaleOf(it).one; }

  // A stored value as text, in engineering units.
  function format(it, v) {
    if (v === null || v === undefined) return "–";
    if (typeof v === "string") return v;                      // NaN, Infinity
    if (it.type === "bool") return v ? "on" : "off";
    if (it.type === "float32") return String(Number(v.toPrecision(7)));
    if (isScaled(it)) return scaledText(it, v);
    return String(v);
  }

  // A stored value as a number for the plots (bool: 0/1).
  function plotValue(it, v) {
    if (typeof v === "boolean") return v ? 1 : 0;
    if (typeof v !== "number") return null;
    return isScaled(it) ? Number(scaledText(it, v)) : v;
  }

  const withUnit = (it, text) => text + (it.unit ? " " + it.unit : "");

  function rangeText(it) {
    return it.range ? `range ${format(it, it.range[0])}..${format(it, it.range[1])}` : "";
  }

  // Typed text as the server reads it: a phone's decimal comma becomes a point.
  function typed(it, text) {
    const t = text.trim();
    return it.type === "float32" || isScaled(it) ? t.replace(",", ".") : t;
  }

  // The stored value of engineering text: {stored: BigInt} or {error}.
  function storedOf(it, text) {
    const m = DECIMAL.exec(text);
    if (!m) return { error: `'${text}' is not a decimal number for ${it.name}: not sent` };
    const [whole, frac = ""] = m[2].split(".");
    const s = scaleOf(it);
    let num = BigInt((whole + frac) || "0");
    let den = s.digits;
    const shift = Number(m[3] || 0) - frac.length + s.decimals;   // value x 10^decimals / digits
    if (shift >= 0) num *= 10n ** BigInt(shift); else den *= 10n ** BigInt(-shift);
    if (num % den !== 0n) {
      return { error: `${text} is not a multiple of the scale ${it.scale} of ${it.name}: it cannot be stored exactly, not sent` };
    }
    return { stored: (m[1] === "-" ? -1n : 1n) * (num / den) };
  }

  // The value a text stands for, in stored units, or null when the server had better judge it.
  function numberOf(it, text) {
    const t = text.trim();
    if (it.type === "float32") return t === "" || Number.isNaN(Number(t)) ? null : Number(t);
    if (it.type === "time") {
      const m = /^(\d+(?:\.\d+)?)\s*(ms|s|min|m|h)?$/.exec(t);
      return m ? parseFloat(m[1]) * TIME_UNITS[m[2] || "ms"] : null;
    }
    return /^[+-]?(0x[0-9a-f]+|\d+)$/i.test(t) ? parseInt(t, t.toLowerCase().includes("0x") ? 16 : 10) : null;
  }

  // The checks before sending: a message when the value is refused here.
  function checkValue(it, text) {
    if (it.type === "bool") return null;
    if (text === "") return "give a value";
    let v;
    if (isScaled(it)) {
      const r = storedOf(it, text);
      if (r.error) return r.error;
      v = r.stored;
    } else {
      v = numberOf(it, text);
      if (v === null) return null;
    }
    const [lo, hi] = it.range || TYPE_LIMITS[it.type] || [-Infinity, Infinity];
    if (v < lo || v > hi) {
      return `${text} is outside the range of ${it.name} (${withUnit(it, `${format(it, lo)}..${format(it, hi)}`)}): not sent`;
    }
    return null;
  }

  // Whether an item's values may be negative: such fields get a sign key.
  function mayBeNegative(it) {
    if (it.range) return it.range[0] < 0;
    return it.type === "float32" || (TYPE_LIMITS[it.type] || [0])[0] < 0;
  }

  panel.units = { format, storedOf, checkValue, typed };   // for the tests' property checks

  // ------------------------------------------------------------------ items

  function valueInput(it) {
    if (it.type === "bool") {
      return el("select", { name: "value", "aria-label": `new value of ${it.name}` },
        el("option", { value: "1", text: "on" }), el("option", { value: "0", text: "off" }));
    }
    // "decimal" brings a keypad with a point (or a comma); "numeric" digits only.
    // Neither has a minus on every phone: items that may be negative get a ± key.
    const decimals = it.type === "float32" || (isScaled(it) && scaleOf(it).decimals > 0);
    return el("input", { name: "value", type: "text", inputmode: decimals ? "decimal" : "numeric",
      enterkeyhint: "send", autocomplete: "off", autocorrect: "off", autocapitalize: "none", spellcheck: "false",
      "aria-label": `new value of ${it.name}`,
      placeholder: it.range ? `${format(it, it.range[0])}..${format(it, it.range[1])}` : it.type });
  }

  function toggleSign(input) {
    const t = input.value.trim();
    input.value = t.startsWith("-") ? t.slice(1) : (t.startsWith("+") ? "-" + t.slice(1) : "-" + t);
    input.classList.remove("invalid");
    input.focus();
  }

  function itemRow(it, index) {
    const value = el("span", { class: "value", text: "–" });
    const plotButton = el("button", { type: "button", class: "plot-toggle", "aria-pressed": "false", text: "Plot" });
    const row = el("div", { class: "item stale" + (it.alarm ? " alarm" : ""), "data-item": it.name },
      el("div", { class: "head" }, el("span", { class: "name", text: it.name }),
        it.persist ? el("span", { class: "badge", title: "kept across resets", text: "persist" }) : null,
        it.access === "ro" ? el("span", { class: "badge", title: "read-only", text: "ro" }) : null, plotButton),
      el("div", { class: "reading" }, value, " ", el("span", { class: "unit", text: it.unit || "" })),
      el("div", { class: "meta", text: [it.type, rangeText(it)].filter(Boolean).join(" · ") }));
    const entry = { it, index, row, value, plotButton, msg: null };
    if (it.access === "rw") {
      const input = valueInput(it);
      const form = el("form", { class: "edit" }, input);
      if (it.type !== "bool" && mayBeNegative(it)) {
        const sign = el("button", { type: "button", class: "sign secondary", "aria-label": `change the sign of the new value of ${it.name}`, text: "±" });
        sign.addEventListener("click", () => toggleSign(input));
        form.append(sign);
      }
      form.append(el("button", { type: "submit", class: "set", text: "Set" }));
      entry.msg = el("div", { class: "msg", role: "status" });
      row.append(form, entry.msg);
      form.addEventListener("submit", (ev) => { ev.preventDefault(); submitEdit(entry, input); });
      input.addEventListener("input", () => input.classList.remove("invalid"));
    }
    plotButton.addEventListener("click", () => togglePlot(entry));
    return entry;
  }

  function showValue(entry, v) {
    entry.value.textContent = format(entry.it, v);
    if (entry.it.alarm) entry.row.classList.toggle("alarm-on", v === true || (typeof v === "number" && v !== 0));
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
    panel.raw = map.items.map(() => []);
  }

  async function submitEdit(entry, input) {
    const text = typed(entry.it, input.value);
    const refused = checkValue(entry.it, text);
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
      showLinkMsg(entry.msg, "the panel server does not answer; nothing was sent");
      return false;
    }
    if (!r.ok) {
      showRefusal(entry.msg, r, "");
      return false;
    }
    showValue(entry, r.data.value);
    entry.writtenAfter = r.data.seq;  // samples up to this one were read before the write
    const shown = withUnit(entry.it, format(entry.it, r.data.value));
    showMsg(entry.msg, true, `set: ${entry.it.name} = ${shown}`);
    panel.marks.push({ t: r.data.t, name, text: shown });
    for (const chart of panel.charts) if (chart.plot) chart.plot.redraw(false, false);
    return true;
  }
  panel.send = send;

  // ------------------------------------------------------------------ plots

  // A plot ("chart") holds several items; bools are drawn as states (on/off
  // bands on their own scale), alarms in red; a dashed line marks each write.
  // Plots follow the samples unless paused or zoomed (drag to zoom, double
  // click or "Live" to follow again).

  function storageKey() { return `easylab-panel:${panel.map.model}:plots`; }

  function savePlots() {
    try { localStorage.setItem(storageKey(), JSON.stringify(panel.charts.map((c) => c.names))); } catch (_) { /* private mode */ }
  }

  // The saved plots (a list of name lists; a plain name is a plot of its own).
  function chosenPlots() {
    try {
      const saved = JSON.parse(localStorage.getItem(storageKey()) || "null");
      if (Array.isArray(saved)) {
        return saved.map((c) => (Array.isArray(c) ? c : [c]).filter((n) => panel.rows.has(n))).filter((c) => c.length);
      }
    } catch (_) { /* none saved */ }
    const first = panel.map.items.find((it) => it.kind === "var" && it.access === "ro" && it.type !== "bool");
    return first ? [[first.name]] : [];
  }

  function plotWidth(holder) { return Math.max(200, holder.clientWidth); }

  const chartOf = (name) => panel.charts.find((c) => c.names.includes(name));

  function togglePlot(entry) {
    const chart = chartOf(entry.it.name);
    if (chart) removeSeries(chart, entry.it.name);
    else addSeries(panel.charts[panel.charts.length - 1] || newChart(), entry.it.name);
    savePlots();
  }

  function newChart() {
    const chart = { names: [], plot: null, zoomed: false, marksDrawn: 0 };
    chart.holder = el("div", { class: "holder" });
    chart.legend = el("div", { class: "legend" });
    chart.add = el("select", { class: "add", "aria-label": "add an item to this plot" });
    const csv = el("button", { type: "button", class: "secondary csv", text: "CSV", title: "download what this plot shows" });
    const close = el("button", { type: "button", class: "secondary close", "aria-label": "remove this plot", text: "×" });
    chart.card = el("div", { class: "plot" }, el("div", { class: "plot-head" }, chart.legend, chart.add, csv, close), chart.holder);
    $("plot-list").append(chart.card);
    $("plots-hint").hidden = true;
    chart.add.addEventListener("change", () => {
      if (chart.add.value) { addSeries(chart, chart.add.value); savePlots(); }
    });
    csv.addEventListener("click", () => downloadCsv(chart));
    close.addEventListener("click", () => { removeChart(chart); savePlots(); });
    chart.holder.addEventListener("dblclick", () => unzoom(chart));
    panel.charts.push(chart);
    fillAddChoices(chart);
    return chart;
  }

  function removeChart(chart) {
    if (chart.plot) chart.plot.destroy();
    chart.card.remove();
    panel.charts.splice(panel.charts.indexOf(chart), 1);
    for (const name of chart.names) markPlotted(name, false);
    $("plots-hint").hidden = panel.charts.length > 0;
  }

  function addSeries(chart, name) {
    const other = chartOf(name);
    if (other === chart) return;
    if (other) removeSeries(other, name);
    chart.names.push(name);
    markPlotted(name, true);
    rebuildChart(chart);
  }

  function removeSeries(chart, name) {
    chart.names = chart.names.filter((n) => n !== name);
    markPlotted(name, false);
    if (!chart.names.length) removeChart(chart); else rebuildChart(chart);
  }

  function markPlotted(name, on) {
    const entry = panel.rows.get(name);
    entry.plotButton.setAttribute("aria-pressed", String(on));
    entry.plotButton.textContent = on ? "Plotted" : "Plot";
    for (const chart of panel.charts) fillAddChoices(chart);
  }

  function fillAddChoices(chart) {
    chart.add.replaceChildren(el("option", { value: "", text: "+ item" }),
      ...panel.map.items.filter((it) => !chart.names.includes(it.name))
        .map((it) => el("option", { value: it.name, text: it.name })));
  }

  function seriesColor(it, k) { return it.alarm ? ALARM_COLOR : COLORS[k % COLORS.length]; }

  function seriesOpts(it, k) {
    const color = seriesColor(it, k);
    if (it.type === "bool") {                                   // a state: a filled on/off band
      return { label: it.name, scale: "state", stroke: color, width: 1.5, fill: color + "33",
        paths: uPlot.paths.stepped({ align: 1 }), points: { show: false } };
    }
    return { label: it.name, scale: "y", stroke: color, width: 2, points: { show: false } };
  }

  // Write marks: a dashed vertical line and the written value at each write.
  function drawMarks(u, chart) {
    const [lo, hi] = [u.scales.x.min, u.scales.x.max];
    const ctx = u.ctx;
    let drawn = 0;
    ctx.save();
    ctx.strokeStyle = "#b26a00";
    ctx.fillStyle = "#b26a00";
    ctx.lineWidth = 1;
    ctx.setLineDash([4, 3]);
    ctx.font = `${Math.round(11 * devicePixelRatio)}px system-ui, sans-serif`;
    for (const mark of panel.marks) {
      if (lo === undefined || mark.t < lo || mark.t > hi) continue;
      const x = Math.round(u.valToPos(mark.t, "x", true));
      ctx.beginPath();
      ctx.moveTo(x, u.bbox.top);
      ctx.lineTo(x, u.bbox.top + u.bbox.height);
      ctx.stroke();
      ctx.fillText(`${mark.name} = ${mark.text}`, x + 3, u.bbox.top + 12 * devicePixelRatio);
      drawn += 1;
    }
    ctx.restore();
    chart.marksDrawn = drawn;
  }

  function rebuildChart(chart) {
    if (chart.plot) chart.plot.destroy();
    chart.plot = null;
    const items = chart.names.map((n) => panel.rows.get(n).it);
    const numeric = items.some((it) => it.type !== "bool");
    const states = items.some((it) => it.type === "bool");
    chart.legend.replaceChildren(...items.map((it, k) => {
      const remove = el("button", { type: "button", class: "remove", "aria-label": `stop plotting ${it.name}`, text: "×" });
      remove.addEventListener("click", () => { removeSeries(chart, it.name); savePlots(); });
      const swatch = el("span", { class: "swatch" });
      swatch.style.background = seriesColor(it, k);            // CSSOM: the page's CSP allows no style attributes
      return el("span", { class: "series" + (it.alarm ? " alarm" : ""), "data-series": it.name }, swatch,
        el("span", { text: it.name + (it.unit ? ` [${it.unit}]` : "") }), el("span", { class: "last" }), remove);
    }));
    const axes = [{ stroke: "#5d6a74" }];
    if (numeric) axes.push({ scale: "y", stroke: "#5d6a74", size: 56 });
    if (states) {
      axes.push({ scale: "state", side: numeric ? 1 : 3, stroke: "#5d6a74", size: 36, splits: () => [0, 1],
        values: (u, splits) => splits.map((v) => (v === 1 ? "on" : v === 0 ? "off" : "")), grid: { show: !numeric } });
    }
    const opts = {
      width: plotWidth(chart.holder), height: PLOT_HEIGHT, legend: { show: false },
      cursor: { drag: { x: true, y: false, setScale: true } },
      scales: { x: { time: true }, y: { auto: true }, state: { auto: false, range: [-0.15, 1.15] } },
      series: [{}, ...items.map(seriesOpts)], axes,
      hooks: {
        draw: [(u) => drawMarks(u, chart)],
        setSelect: [(u) => { if (u.select.width > 0) chart.zoomed = true; }],
      },
    };
    chart.plot = new uPlot(opts, chartData(chart), chart.holder);
    touchZoom(chart);
    fillAddChoices(chart);
    showLast(chart);
  }

  // Copies: a paused or zoomed plot keeps what it shows while the samples go on.
  // Zoom by touch (uPlot's own drag zoom takes a mouse): drag a finger across
  // a plot to zoom in on that span, tap twice to follow the samples again.
  function touchZoom(chart) {
    const u = chart.plot;
    const over = u.over;
    let startX = null;
    let lastTap = 0;
    const xOf = (ev) => ev.changedTouches[0].clientX - over.getBoundingClientRect().left;
    over.addEventListener("touchstart", (ev) => { startX = ev.touches.length === 1 ? xOf(ev) : null; }, { passive: true });
    over.addEventListener("touchmove", (ev) => {
      if (startX === null) return;
      const x = xOf(ev);
      u.setSelect({ left: Math.min(startX, x), width: Math.abs(x - startX), top: 0, height: over.clientHeight }, false);
    }, { passive: true });
    over.addEventListener("touchend", (ev) => {
      if (startX === null) return;
      const x = xOf(ev);
      const [left, right] = [Math.min(startX, x), Math.max(startX, x)];
      startX = null;
      u.setSelect({ left: 0, width: 0, top: 0, height: 0 }, false);
      if (right - left >= 8) {
        chart.zoomed = true;
        u.setScale("x", { min: u.posToVal(left, "x"), max: u.posToVal(right, "x") });
      } else if (ev.timeStamp - lastTap < 350) {
        unzoom(chart);
      }
      lastTap = ev.timeStamp;
    });
  }

  // Back to the whole of what the plot holds (paused: the same samples).
  function unzoom(chart) {
    chart.zoomed = false;
    if (chart.plot) chart.plot.setData(chart.plot.data, true);
  }

  function chartData(chart) {
    return [panel.times.slice(), ...chart.names.map((n) => panel.series[panel.rows.get(n).index].slice())];
  }

  function showLast(chart) {
    const n = panel.times.length;
    for (const name of chart.names) {
      const entry = panel.rows.get(name);
      const last = chart.legend.querySelector(`[data-series="${CSS.escape(name)}"] .last`);
      if (last) last.textContent = n ? format(entry.it, panel.raw[entry.index][n - 1]) : "";
    }
  }

  // Redraw the plots with the newest samples (none while paused; a zoomed plot keeps its span).
  function drawPlots(newSamples) {
    for (const chart of panel.charts) {
      if (!chart.plot || (panel.paused && newSamples)) continue;
      chart.plot.setData(chartData(chart), !chart.zoomed);
      showLast(chart);
    }
  }

  function setPaused(on) {
    panel.paused = on;
    $("plot-pause").setAttribute("aria-pressed", String(on));
    $("plot-pause").textContent = on ? "Resume" : "Pause";
    $("plots").classList.toggle("paused", on);
    if (!on) drawPlots(true);
  }

  function followLive() {
    for (const chart of panel.charts) chart.zoomed = false;
    setPaused(false);
  }

  // ------------------------------------------------------------------ CSV of a plot

  // What a plot shows: its items over its visible span, in engineering units.
  function csvOf(chart) {
    const items = chart.names.map((n) => panel.rows.get(n));
    const u = chart.plot;
    const lo = u.scales.x.min, hi = u.scales.x.max;
    const quote = (t) => (/[",\n]/.test(t) ? `"${t.replace(/"/g, '""')}"` : t);
    const lines = [["time", "unix_s", ...items.map((e) => e.it.name + (e.it.unit ? ` [${e.it.unit}]` : ""))].map(quote).join(",")];
    panel.times.forEach((t, k) => {
      if (t < lo || t > hi) return;
      const cells = items.map((e) => {
        const v = panel.raw[e.index][k];
        if (v === null || v === undefined) return "";                // a gap: the device was away
        return e.it.type === "bool" ? (v ? "1" : "0") : format(e.it, v);
      });
      lines.push([new Date(t * 1000).toISOString(), t.toFixed(3), ...cells].join(","));
    });
    return lines.join("\n") + "\n";
  }
  panel.csvOf = csvOf;

  function downloadCsv(chart) {
    if (!chart.plot) return;
    const name = `${panel.map.model}-plot-${panel.charts.indexOf(chart) + 1}.csv`;
    const url = URL.createObjectURL(new Blob([csvOf(chart)], { type: "text/csv" }));
    const a = el("a", { href: url, download: name });
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
  }

  window.addEventListener("resize", () => {
    for (const chart of panel.charts) if (chart.plot) chart.plot.setSize({ width: plotWidth(chart.holder), height: PLOT_HEIGHT });
  });

  // ------------------------------------------------------------------ samples and the link

  function pushRow(t, values) {
    panel.times.push(t);
    panel.map.items.forEach((it, k) => {
      const v = values ? values[k] : null;
      panel.raw[k].push(v);
      panel.series[k].push(values ? plotValue(it, v) : null);
    });
  }

  function addSamples(samples) {
    for (const s of samples) {
      // The device was away before this sample: a null row breaks the lines there.
      if (s.gap && panel.times.length) pushRow((panel.times[panel.times.length - 1] + s.t) / 2, null);
      pushRow(s.t, s.v);
      panel.lastSeq = s.seq;
    }
    const extra = panel.times.length - MAX_POINTS;
    if (extra > 0) {
      panel.times.splice(0, extra);
      for (const column of panel.series) column.splice(0, extra);
      for (const column of panel.raw) column.splice(0, extra);
    }
    const latest = samples[samples.length - 1];
    if (latest) {
      for (const entry of panel.rows.values()) {
        // A sample taken before the item's last write would show the old value again.
        if (entry.writtenAfter !== undefined && latest.seq <= entry.writtenAfter) continue;
        showValue(entry, latest.v[entry.index]);
      }
      panel.lastTime = latest.t;
    }
    if (samples.length) drawPlots(true);
  }

  function showLink(link, now) {
    const back = link.state === "connected" && (!panel.link || panel.link.state !== "connected" || panel.serverOk === false);
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
      if (back) clearLinkMsgs();
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
      addSamples(r.data.samples);
      showLink(r.data.link, r.data.now);
      panel.serverOk = true;
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
      showLinkMsg(msg, "the panel server does not answer");
      return;
    }
    if (!response.ok) {
      let data = null;
      try { data = await response.json(); } catch (_) { /* not JSON */ }
      showRefusal(msg, { status: response.status, data }, "no backup: ");
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
      showLinkMsg(msg, "the panel server does not answer; nothing was restored");
      return;
    }
    if (!r.ok) {
      showRefusal(msg, r, "not restored: ");
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
    for (const names of chosenPlots()) {
      const chart = newChart();
      for (const name of names) addSeries(chart, name);
    }
    $("plot-pause").addEventListener("click", () => setPaused(!panel.paused));
    $("plot-live").addEventListener("click", followLive);
    $("plot-new").addEventListener("click", () => { newChart(); savePlots(); });
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
