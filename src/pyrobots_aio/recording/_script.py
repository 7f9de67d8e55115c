"""The replay page's only script: static text that reads the ``data-`` attributes the page sets.

What it does, on the figures that share the time axis (``svg[data-x0]``):

- **cursor**: the mouse over a figure, or over the map's path, shows that
  moment on every figure, puts the map's "here" circle and heading arrow where
  the robot was, and fills the readout (``div.readout``) with the value of
  each plotted row then: a number as drawn (``data-values``), a flag from its
  pulses (``data-t0``, ``data-t1``);
- **zoom and pan**: the wheel over the plot area zooms about the mouse (at
  most `MAX_ZOOM` times), a drag pans, a double-click or the "reset zoom"
  button shows the whole run again; every figure follows. What a figure draws
  on the time axis sits in its ``svg.zoom``, whose shapes move (their
  original x is kept) and whose lines are rescaled; a bar's label that did
  not fit shows once the bar is ``data-fit`` times wider; the time axis is
  drawn again with round steps (1, 2 or 5 times a power of ten, as `_svg.ticks`).
  Each figure's ``data-view`` holds the seconds shown ("from to").

Built only with ``textContent`` and ``setAttribute``: text from the recording
never becomes markup.
"""

MAX_ZOOM = 50
"""Most magnification: the page holds one pixel column's first, lowest, highest and last value."""
WHEEL = 0.002
"""Zoom per pixel of wheel: one notch (100 pixels) shows e^0.2 (about 1.22) times less time."""

SCRIPT = (
    """
(function () {
  "use strict";
  var timed = Array.prototype.slice.call(document.querySelectorAll("svg[data-x0]"));
  var map = document.querySelector("svg.map"), readout = document.querySelector(".readout");
  if (!timed.length) { return; }
  var x0 = +timed[0].dataset.x0, w = +timed[0].dataset.w, span = +timed[0].dataset.duration;
  var MAX_ZOOM = """
    + str(MAX_ZOOM)
    + """, WHEEL = """
    + str(WHEEL)
    + """, NS = "http://www.w3.org/2000/svg";
  var view = {a: 0, b: span}, now = null, drag = null;
  var track = [], here = null, arrow = null, ox = 0, oy = 0, k = 1;
  if (map) {
    here = map.querySelector(".here"); arrow = map.querySelector(".here-heading");
    ox = +map.dataset.ox; oy = +map.dataset.oy; k = +map.dataset.scale;
    track = (map.dataset.track || "").split(";").filter(Boolean).map(function (s) {
      return s.split(",").map(Number);
    });
  }
  function each(selector, fn) {
    return Array.prototype.map.call(document.querySelectorAll(selector), fn);
  }
  function local(svg, ev) {
    var p = svg.createSVGPoint(); p.x = ev.clientX; p.y = ev.clientY;
    return p.matrixTransform(svg.getScreenCTM().inverse());
  }
  function last(list, value, key) {
    // The index of the last item whose key is at most value (-1: none); list sorted by key.
    var lo = -1, hi = list.length - 1;
    while (lo < hi) {
      var mid = (lo + hi + 1) >> 1;
      if (key(list[mid]) <= value) { lo = mid; } else { hi = mid - 1; }
    }
    return lo;
  }
  function first(item) { return item[0]; }
  function niceStep(length, most) {
    if (!(length > 0)) { return 1; }
    var raw = length / most, base = Math.pow(10, Math.floor(Math.log10(raw)));
    return [1, 2, 5, 10].map(function (f) { return f * base; }).filter(function (s) {
      return s >= raw;
    })[0];
  }
  function decimals(step) { return Math.max(0, -Math.floor(Math.log10(step))); }
  function tickText(value, step) {
    var d = decimals(step);
    if (d > 6 || Math.abs(value) >= 1e9) { return String(+value.toPrecision(3)); }
    var text = value.toFixed(d);
    return +text === 0 ? "0" : text;
  }
  function add(parent, tag, attributes) {
    var el = document.createElementNS(NS, tag);
    Object.keys(attributes).forEach(function (name) { el.setAttribute(name, attributes[name]); });
    parent.appendChild(el);
    return el;
  }

  // What each row plotted held, for the readout.
  var lines = new Map(), pulses = new Map();
  each("svg.timeline polyline.plot", function (el) {
    var points = el.getAttribute("points").split(" ");
    var values = (el.dataset.values || "").split(" ").filter(Boolean);
    // A row steps to each value: its points are x0 then two per value (held, new).
    lines.set(el.dataset.key, {values: values, xs: values.map(function (_, i) {
      return +points[2 * i].split(",")[0];
    })});
  });
  each("svg.timeline rect.plot.bool", function (el) {
    if (!pulses.has(el.dataset.key)) { pulses.set(el.dataset.key, []); }
    pulses.get(el.dataset.key).push([+el.dataset.t0, +el.dataset.t1]);
  });
  var stamp = null, rows = [];
  if (readout) {
    stamp = readout.appendChild(document.createElement("span"));
    rows = each("svg.timeline text.label[data-key]", function (el) {
      var item = readout.appendChild(document.createElement("span"));
      item.dataset.key = el.dataset.key;
      var flag = el.dataset.kind === "flag";
      return {key: el.dataset.key, unit: el.dataset.unit, flag: flag, item: item};
    });
  }
  function valueAt(row, t) {
    if (row.flag) {
      var spells = pulses.get(row.key) || [], i = last(spells, t, first);
      // A pulse still on when the recording ended holds to its very end (times to 1 ms).
      return i >= 0 && (t < spells[i][1] || spells[i][1] >= span - 5e-4) ? "true" : "false";
    }
    var line = lines.get(row.key), x = x0 + (span > 0 ? t / span * w : 0);
    var j = line ? last(line.xs, x + 1e-6, Number) : -1;
    return j < 0 ? "-" : line.values[j] + (row.unit ? " " + row.unit : "");
  }

  function show(t) {
    now = t;
    var inside = t >= view.a && t <= view.b;
    var x = x0 + (span > 0 ? (t - view.a) / (view.b - view.a) * w : 0);
    timed.forEach(function (svg) {
      var line = svg.querySelector(".cursor"), label = svg.querySelector(".cursor-time");
      if (line) {
        line.setAttribute("x1", x); line.setAttribute("x2", x);
        line.style.display = inside ? "" : "none";
      }
      if (label) {
        label.setAttribute("x", x + 4);
        label.textContent = inside ? t.toFixed(2) + " s" : "";
      }
    });
    if (here && track.length) {
      var p = track[Math.max(0, last(track, t, first))], cx = ox + p[1] * k, cy = oy - p[2] * k;
      here.setAttribute("cx", cx); here.setAttribute("cy", cy);
      if (arrow) {
        arrow.setAttribute("transform", "translate(" + cx + "," + cy + ") rotate(" +
          (-(p[3] || 0) * 180 / Math.PI) + ")");
      }
    }
    if (stamp) {
      readout.hidden = false;
      stamp.textContent = "t " + t.toFixed(3) + " s";
      rows.forEach(function (row) { row.item.textContent = row.key + " " + valueAt(row, t); });
    }
  }

  // Zoom: every figure's shapes on the time axis, with their original x.
  var figures = timed.map(function (svg) {
    var zoom = svg.querySelector("svg.zoom");
    var shapes = zoom ? zoom.querySelectorAll("rect, line, text, path, polyline") : [];
    return {svg: svg, axis: svg.querySelector("g.axis.time"), shapes: Array.prototype.map.call(
      shapes, function (el) {
        var move = /translate\\(([^,]+),([^)]+)\\)/.exec(el.getAttribute("transform") || "");
        return {el: el, tag: el.tagName, move: move, x: +el.getAttribute("x"),
          width: +el.getAttribute("width"), x1: +el.getAttribute("x1"), x2: +el.getAttribute("x2"),
          fit: +(el.dataset.fit || 0)};
      })};
  });
  function magnification() { return span / (view.b - view.a); }
  function place(x) { return x0 + (x - x0 - view.a / span * w) * magnification(); }
  function drawAxis(axis) {
    while (axis.childNodes.length > 1) { axis.removeChild(axis.lastChild); }
    var step = niceStep(view.b - view.a, 12), d = axis.dataset;
    for (var i = Math.ceil(view.a / step - 1e-9); i * step <= view.b + step * 1e-9; i++) {
      var x = x0 + (i * step - view.a) / (view.b - view.a) * w;
      var label = add(axis, "text", {x: x, y: d.labelY, "text-anchor": "middle"});
      label.textContent = tickText(i * step, step);
      add(axis, "line", {"class": "grid", x1: x, y1: d.top, x2: x, y2: d.bottom});
    }
  }
  function redraw() {
    var z = magnification(), shift = x0 - (x0 + view.a / span * w) * z;
    figures.forEach(function (figure) {
      figure.shapes.forEach(function (s) {
        var el = s.el;
        if (s.tag === "rect") {
          el.setAttribute("x", place(s.x)); el.setAttribute("width", s.width * z);
        } else if (s.tag === "line") {
          el.setAttribute("x1", place(s.x1)); el.setAttribute("x2", place(s.x2));
        } else if (s.tag === "text") {
          el.setAttribute("x", place(s.x));
          if (s.fit) { el.style.display = z >= s.fit ? "inline" : ""; }
        } else if (s.tag === "polyline") {
          el.setAttribute("transform", "translate(" + shift + ",0) scale(" + z + ",1)");
        } else if (s.move) {
          el.setAttribute("transform", "translate(" + place(+s.move[1]) + "," + s.move[2] + ")");
        }
      });
      if (figure.axis) { drawAxis(figure.axis); }
      figure.svg.dataset.view = view.a + " " + view.b;
    });
    var note = document.querySelector(".zoombar .view");
    if (note) {
      var d = decimals(niceStep(view.b - view.a, 12));
      note.textContent = z > 1 ? "showing " + view.a.toFixed(d) + " to " + view.b.toFixed(d) +
        " s (" + z.toFixed(1) + "x)" : "showing the whole run";
    }
    if (now !== null) { show(now); }
  }
  function setView(a, b) {
    var least = span / MAX_ZOOM;
    if (b - a < least) { a = (a + b - least) / 2; b = a + least; }
    if (b - a > span) { a = 0; b = span; }
    if (a < 0) { b -= a; a = 0; }
    if (b > span) { a -= b - span; b = span; }
    view.a = Math.max(0, a); view.b = b;
    redraw();
  }
  function timeAt(x) { return view.a + (x - x0) / w * (view.b - view.a); }
  function inPlot(p) { return p.x >= x0 && p.x <= x0 + w; }

  timed.forEach(function (svg) {
    svg.addEventListener("mousemove", function (ev) {
      var p = local(svg, ev);
      if (inPlot(p)) { show(timeAt(p.x)); }
    });
    if (!(span > 0)) { return; }
    svg.addEventListener("wheel", function (ev) {
      var p = local(svg, ev);
      if (!inPlot(p)) { return; }  // over the labels, the wheel scrolls the page
      ev.preventDefault();
      var unit = ev.deltaMode === 1 ? 33 : ev.deltaMode === 2 ? 600 : 1;
      var t = timeAt(p.x), length = (view.b - view.a) * Math.exp(ev.deltaY * unit * WHEEL);
      length = Math.min(span, Math.max(span / MAX_ZOOM, length));
      var a = t - (p.x - x0) / w * length + ev.deltaX * unit / w * length;
      setView(a, a + length);
      show(t);
    }, {passive: false});
    svg.addEventListener("mousedown", function (ev) {
      var p = local(svg, ev);
      if (ev.button !== 0 || !inPlot(p)) { return; }
      ev.preventDefault();  // no text selection while dragging
      drag = {svg: svg, x: p.x, a: view.a, b: view.b};
      svg.classList.add("dragging");
    });
    svg.addEventListener("dblclick", function (ev) {
      if (inPlot(local(svg, ev))) { setView(0, span); }
    });
  });
  window.addEventListener("mousemove", function (ev) {
    if (!drag) { return; }
    var shift = (local(drag.svg, ev).x - drag.x) / w * (drag.b - drag.a);
    setView(drag.a - shift, drag.b - shift);
  });
  window.addEventListener("mouseup", function () {
    if (drag) { drag.svg.classList.remove("dragging"); drag = null; }
  });
  var reset = document.querySelector(".reset-zoom");
  if (reset) { reset.addEventListener("click", function () { setView(0, span); }); }
  if (span > 0) { redraw(); }

  if (map && track.length) {
    map.addEventListener("mousemove", function (ev) {
      var p = local(map, ev), x = (p.x - ox) / k, y = (oy - p.y) / k, best = -1, least = 0.09;
      track.forEach(function (q, i) {
        var d = (q[1] - x) * (q[1] - x) + (q[2] - y) * (q[2] - y);
        if (d < least) { least = d; best = i; }
      });
      if (best >= 0) { show(track[best][0]); }
    });
  }
})();
"""
)
"""The script itself (see the module notes)."""
