"""``sweep explore``: an atlas as one self-contained HTML page to explore offline.

Bokeh's standalone output with its scripts inlined (no network, opened by a double click);
the views share one table of designs, so a selection in one is a selection in all:

- a 2-D chart of any two variables (grid axes first) coloured by any variable, at the
  values of the other grid axes set by menus ("all" shows every value: the cloud);
- a scatter matrix of up to four variables, where a box or lasso brushes designs, and a
  range per variable that selects the designs inside every range;
- the picked design of a front marked in every view;
- hover on a design: its parameters and outputs with units; a table of the selected
  designs and a CSV download.

Statuses and requirements are coloured as in the static charts (sweep.palettes), numbers on
the sequential map, signed ones on the diverging map centred on 0, a design without a value
grey. Up to ``MAX_DESIGNS`` designs every one is shown; beyond, every k-th in grid order,
which the page says (never a silent drop). Only small callbacks are written by hand."""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from sweep.errors import UserError

#: every design shown up to this many; beyond, every k-th in grid order (the page says so)
MAX_DESIGNS = 100_000
#: variables of the scatter matrix at most (its lower triangle: 6 panels)
MATRIX_VARIABLES = 4
#: a design without a value of the colour variable
NO_VALUE = "#BBBBBB"
ROW = "grid_point"  # the design's flat (C-order) index in the atlas's grid


def table(ds: xr.Dataset, max_designs: int = MAX_DESIGNS):
    """The atlas as columns of one row per design (every k-th beyond ``max_designs``):
    (columns {name: values as shown}, meta {name: label, units, kind, ...}, step k,
    number of grid points). Angles in degrees, flags as their meanings."""
    from sweep import labels
    from sweep.palettes import CATEGORY_COLOURS, flag_colours
    from sweep.selection import flag_names

    dims = list(ds["status"].dims)
    shape = ds["status"].shape
    total = math.prod(shape)
    step = max(1, math.ceil(total / max_designs))
    keep = np.arange(0, total, step)
    index = np.unravel_index(keep, shape)
    columns, meta = {ROW: keep.astype(np.int64)}, {ROW: {
        "label": "grid point", "units": "", "kind": "number", "axis": False}}
    names = dims + [str(n) for n in ds.variables if str(n) not in dims]
    for name in names:
        var = ds[name]
        if not set(var.dims) <= set(dims) or name in columns:
            continue  # a profile, or a coordinate of a profile axis
        flat = var.broadcast_like(ds["status"]).transpose(*dims).values.ravel()[keep] \
            if var.ndim else np.full(keep.size, var.values)
        item = {"label": labels.plain(labels.label(ds, name)), "axis": name in dims,
                "units": labels.pretty_units(labels.units(ds, name, True))}
        if "flag_meanings" in var.attrs:
            meanings = flag_names(var)
            shown = [meanings.get(int(code), "") for code in flat]
            colours = flag_colours(name, meanings)
            order = sorted(meanings)
            item.update(kind="category", categories=[meanings[c] for c in order],
                        colours=[colours[c] for c in order])
            columns[name] = np.array([str(w) for w in shown], dtype=object)
        elif flat.dtype.kind in "OSU":
            shown = np.array([v.decode() if isinstance(v, bytes) else str(v) for v in flat],
                             dtype=object)
            categories = list(dict.fromkeys(
                (v.decode() if isinstance(v, bytes) else str(v))
                for v in np.asarray(var.values).ravel()))
            item.update(kind="category", categories=categories,
                        colours=[CATEGORY_COLOURS[i % len(CATEGORY_COLOURS)]
                                 for i in range(len(categories))])
            columns[name] = shown
        elif flat.dtype.kind in "biuf":
            values = labels.shown_values(var, True, ds)
            values = np.broadcast_to(values, var.shape) if var.ndim else values
            flat = np.asarray(xr.DataArray(values, dims=var.dims).broadcast_like(
                ds["status"]).transpose(*dims).values).ravel()[keep] if var.ndim \
                else np.full(keep.size, float(values))
            flat = flat.astype(np.float64)
            finite = flat[np.isfinite(flat)]
            low, high = (float(finite.min()), float(finite.max())) if finite.size \
                else (0.0, 1.0)
            signed = low < 0.0 < high
            if signed:
                low, high = -max(-low, high), max(-low, high)
            item.update(kind="number", low=low, high=high, signed=signed)
            columns[name] = flat
        else:
            continue
        if item["axis"]:
            item["index"] = f"_i_{name}"
            columns[item["index"]] = index[dims.index(name)].astype(np.int32)
            item["values"] = [_text(v) for v in _axis_values(ds, name, columns, keep)]
        meta[name] = item
    return columns, meta, step, total


def _axis_values(ds, name, columns, keep):
    """The values of a grid axis in its order, as the page shows them."""
    from sweep import labels

    var = ds[name]
    if var.dtype.kind in "OSU":
        return [v.decode() if isinstance(v, bytes) else str(v) for v in var.values]
    return list(np.asarray(labels.shown_values(var, True, ds)).ravel())


def _text(value) -> str:
    return f"{value:.6g}" if isinstance(value, (float, np.floating)) else str(value)


def _palette(name: str) -> list[str]:
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    cmap = colormaps[name]
    return [to_hex(cmap(i / 255.0)) for i in range(256)]


def _defaults(ds, meta, variables):
    """(x, y, colour, matrix variables): the atlas's chart where it names one; a front's
    objectives first in the matrix."""
    spec = json.loads(ds.attrs.get("spec", "{}") or "{}")
    chart = spec.get("chart") or {}
    axes = [n for n, m in meta.items() if m["axis"]]
    numbers = [n for n, m in meta.items() if m["kind"] == "number" and n != ROW
               and not n.startswith("_")]
    outputs = [n for n in numbers if not meta[n]["axis"]]
    pareto = json.loads(ds.attrs.get("pareto", "{}") or "{}")
    objectives = [o.split(" ", 1)[1] for o in pareto.get("objectives", [])]
    if len(objectives) >= 2 and all(o in numbers for o in objectives[:2]):
        chart = {**chart, "x": objectives[0], "y": objectives[1]}  # a front over them
    x = chart.get("x") if chart.get("x") in meta else axes[0]
    y = chart.get("y") if chart.get("y") in meta else \
        (axes[1] if len(axes) > 1 else (outputs[0] if outputs else axes[0]))
    colour = chart.get("color") if chart.get("color") in meta else \
        ("requirements" if "requirements" in meta else "status")
    if variables:
        for name in variables:
            if name not in meta or meta[name]["kind"] != "number" or name == ROW:
                raise UserError(f"variables: {name!r} is not a numeric variable of the "
                                f"atlas; allowed: {', '.join(numbers)}")
        if not 2 <= len(variables) <= MATRIX_VARIABLES:
            raise UserError(f"variables: give 2 to {MATRIX_VARIABLES} variables for the "
                            f"scatter matrix, not {len(variables)}")
        return x, y, colour, list(variables)
    first = objectives + [chart.get("color"), chart.get("overlay")]
    if "requirements" in ds.variables:  # the outputs the limits are on
        limits = json.loads(ds["requirements"].attrs.get("requirements", "[]") or "[]")
        first += [str(text).split()[0] for text in limits]
    order = [n for n in dict.fromkeys(first + outputs + axes) if n in numbers]
    varying = [n for n in order if meta[n]["high"] > meta[n]["low"]]
    return x, y, colour, (varying or order)[:MATRIX_VARIABLES]


def page(ds: xr.Dataset, variables=None, max_designs: int = MAX_DESIGNS) -> str:
    """The explorer of an atlas as one HTML document, every script inlined."""
    from bokeh.document import Document
    from bokeh.embed import file_html
    from bokeh.events import DocumentReady
    from bokeh.layouts import column, gridplot, row
    from bokeh.models import (BooleanFilter, Button, CDSView, ColorBar, ColumnDataSource,
                              CustomJS, DataTable, Div, FixedTicker, HoverTool,
                              LinearColorMapper, RangeSlider, ScientificFormatter, Select,
                              StringFormatter, TableColumn)
    from bokeh.plotting import figure
    from bokeh.resources import INLINE

    columns, meta, step, total = table(ds, max_designs)
    x, y, colour, matrix = _defaults(ds, meta, variables)
    n = len(columns[ROW])
    shown = [name for name in meta]
    data = dict(columns)
    data["_x"] = _position(columns, meta, x)
    data["_y"] = _position(columns, meta, y)
    data["_colour"] = [NO_VALUE] * n
    source = ColumnDataSource(data, name="designs")
    chosen = ColumnDataSource({name: [] for name in shown}, name="chosen")
    in_slice = BooleanFilter(booleans=[True] * n, name="slice_filter")
    sequential, diverging = _palette("viridis"), _palette("RdBu_r")
    mapper = LinearColorMapper(palette=sequential, low=0.0, high=1.0, name="colour_mapper")

    tooltips = [(_title(meta, name), "@{%s}{%%.6g}" % name if meta[name]["kind"] == "number"
                 else "@{%s}" % name) for name in shown]
    formatters = {"@{%s}" % name: "printf" for name in shown
                  if meta[name]["kind"] == "number"}

    def hover():
        return HoverTool(tooltips=tooltips, formatters=formatters)

    options = [(name, _title(meta, name)) for name in shown if name != ROW]
    x_menu = Select(title="across", value=x, options=options, name="x_menu", width=220)
    y_menu = Select(title="up", value=y, options=options, name="y_menu", width=220)
    colour_menu = Select(title="colour", value=colour, options=options, name="colour_menu",
                         width=220)
    axis_menus = []
    # the axes not drawn held at their first value on a chart of two axes; every value
    # (the cloud) where the chart is of outputs
    held = "0" if meta[x]["axis"] and meta[y]["axis"] else "all"
    for name, item in meta.items():
        if item["axis"]:
            choices = [("all", "all")] + [(str(i), v) for i, v in enumerate(item["values"])]
            axis_menus.append(Select(title=_title(meta, name), value=held, options=choices,
                                     name=f"at_{name}", width=160))
    # the canvas backend: WebGL without a GPU is rendered in software, several times slower
    # to a first frame (benchmarks/bench_explorer.py)
    chart = figure(width=620, height=480, tools="pan,wheel_zoom,box_zoom,box_select,"
                   "lasso_select,tap,reset,save", name="slice_plot",
                   title="")
    chart.scatter("_x", "_y", source=source, view=CDSView(filter=in_slice), size=9,
                  marker="square", fill_color="_colour", line_color=None,
                  nonselection_fill_alpha=0.25, name="slice")
    chart.add_tools(hover())
    colour_bar = ColorBar(color_mapper=mapper, width=12, name="colour_bar",
                          title=_title(meta, colour))
    chart.add_layout(colour_bar, "right")
    legend = Div(text="", name="legend", width=620)
    x_ticks, y_ticks = FixedTicker(ticks=[]), FixedTicker(ticks=[])

    panels = []
    for i, row_name in enumerate(matrix):
        cells = []
        for j, col_name in enumerate(matrix):
            if j >= i:
                cells.append(None)
                continue
            panel = figure(width=230, height=230, tools="box_select,lasso_select,reset",
                           name=f"matrix_{col_name}__{row_name}")
            panel.scatter(col_name, row_name, source=source, size=4, fill_color="_colour",
                          line_color=None, nonselection_fill_alpha=0.15,
                          name=f"points_{col_name}__{row_name}")
            panel.add_tools(hover())
            panel.xaxis.axis_label = _title(meta, col_name) if i == len(matrix) - 1 else ""
            panel.yaxis.axis_label = _title(meta, row_name) if j == 0 else ""
            panel.axis.axis_label_text_font_size = "9pt"
            cells.append(panel)
        panels.append(cells)
    matrix_view = gridplot([cells[:-1] for cells in panels[1:]], toolbar_location="right",
                           merge_tools=True)
    ranges = []
    for name in matrix:
        low, high = meta[name]["low"], meta[name]["high"]
        if not high > low:
            high = low + 1.0
        ranges.append(RangeSlider(title=_title(meta, name), start=low, end=high,
                                  value=(low, high), step=(high - low) / 1000.0,
                                  format="0[.]0000", name=f"range_{name}", width=300))
    count = Div(text="", name="count", width=620)
    table_view = DataTable(
        source=chosen, name="table", width=1100, height=260, index_position=None,
        columns=[TableColumn(field=name, title=_title(meta, name),
                             formatter=ScientificFormatter(precision=6)
                             if meta[name]["kind"] == "number" else StringFormatter())
                 for name in shown])
    download = Button(label="Download the selected designs (CSV)", name="download",
                      button_type="primary", width=300)

    picked = _picked(columns)
    if picked is not None:
        mark = ColumnDataSource({k: [v[picked]] for k, v in data.items()
                                 if k != "_colour"}, name="picked")
        chart.scatter("_x", "_y", source=mark, marker="star", size=22,
                      fill_color="#D55E00", line_color="black", name="picked_slice")
        for cells in panels:
            for panel in cells:
                if panel is not None:
                    a, b = panel.name[len("matrix_"):].split("__")
                    panel.scatter(a, b, source=mark, marker="star", size=16,
                                  fill_color="#D55E00", line_color="black")
    else:
        mark = ColumnDataSource({}, name="picked")

    args = dict(source=source, chosen=chosen, in_slice=in_slice, mapper=mapper,
                chart=chart, x_menu=x_menu, y_menu=y_menu, colour_menu=colour_menu,
                axis_menus=axis_menus, legend=legend, count=count, ranges=ranges,
                x_ticks=x_ticks, y_ticks=y_ticks, mark=mark,
                colour_bar=colour_bar, picked_row=-1 if picked is None else picked,
                meta=meta, shown=shown, sequential=sequential, diverging=diverging,
                no_value=NO_VALUE)
    redraw = CustomJS(args=args, code=_JS_COMMON + _JS_REDRAW)
    for menu in [x_menu, y_menu, colour_menu, *axis_menus]:
        menu.js_on_change("value", redraw)
    brushed = CustomJS(args=args, code=_JS_COMMON + _JS_RANGES)
    for slider in ranges:
        slider.js_on_change("value", brushed)
    source.selected.js_on_change("indices", CustomJS(args=args, code=_JS_COMMON + _JS_CHOSEN))
    download.js_on_event("button_click", CustomJS(args=args, code=_JS_COMMON + _JS_CSV))

    header = Div(text=_header(ds, n, step, total, max_designs), name="header",
                 width=1100)
    layout = column(
        header,
        row(column(row(x_menu, y_menu, colour_menu), row(*axis_menus[:6]),
                   *([row(*axis_menus[6:])] if len(axis_menus) > 6 else []), chart, legend),
            column(Div(text="<b>Brush</b> a box or lasso on any panel, or narrow the "
                            "ranges: the selection is the same in every view and the "
                            "table.", width=480),
                   matrix_view, *ranges)),
        count, download, table_view)
    document = Document()
    document.add_root(layout)
    document.js_on_event(DocumentReady, redraw, CustomJS(args=args,
                                                         code=_JS_COMMON + _JS_CHOSEN))
    return file_html(document, resources=INLINE, title=_plain_title(ds))


def _position(columns, meta, name):
    item = meta[name]
    return columns[item["index"]] if item["kind"] == "category" and item["axis"] else \
        columns[name]


def _title(meta, name) -> str:
    item = meta[name]
    return f"{item['label']} [{item['units']}]" if item["units"] else item["label"]


def _picked(columns):
    if "picked" not in columns:
        return None
    hits = np.flatnonzero(columns["picked"] == "yes")
    return int(hits[0]) if hits.size else None


def _plain_title(ds) -> str:
    return str(ds.attrs.get("title", "atlas"))


def _header(ds, n, step, total, max_designs) -> str:
    from html import escape

    shown = (f"every design: {n:,}" if step == 1 else
             f"{n:,} of {total:,} designs: one in every {step}, in grid order (the page "
             f"shows at most {max_designs:,}; a chart or query of the atlas reads them all)")
    return (f"<h2 style='margin:4px 0'>{escape(_plain_title(ds))}</h2>"
            f"<div>{escape(ds.attrs.get('mechanism', ''))} · {shown} · "
            f"{escape(str(ds.attrs.get('code_version', '')))}</div>")


# The page's callbacks: colours and the slice (redraw), ranges to a selection, the
# selection to the table, the table to CSV. ``meta`` holds each variable's label, units,
# kind (number or category), its range or its categories and colours, and for a grid axis
# the column of its value indices.
_JS_COMMON = """
const data = source.data;
function title(name) {
  const m = meta[name];
  return m.units ? `${m.label} [${m.units}]` : m.label;
}
function position(name) {
  const m = meta[name];
  return (m.kind == 'category' && m.axis) ? data[m.index] : data[name];
}
"""

_JS_REDRAW = """
const n = data['grid_point'].length;
const xs = x_menu.value, ys = y_menu.value, cs = colour_menu.value;
// colours
const m = meta[cs], values = data[cs], colours = new Array(n);
if (m.kind == 'category') {
  const table = {};
  m.categories.forEach((c, i) => { table[c] = m.colours[i]; });
  for (let i = 0; i < n; i++) colours[i] = table[values[i]] || no_value;
  colour_bar.visible = false;
  legend.text = m.categories.map((c, i) =>
    `<span style="display:inline-block;width:12px;height:12px;background:${m.colours[i]};` +
    `margin:0 4px 0 10px"></span>${c}`).join('');
} else {
  const palette = m.signed ? diverging : sequential;
  const span = (m.high > m.low) ? m.high - m.low : 1.0;
  for (let i = 0; i < n; i++) {
    const v = values[i];
    if (!Number.isFinite(v)) { colours[i] = no_value; continue; }
    const k = Math.min(255, Math.max(0, Math.floor((v - m.low) / span * 256)));
    colours[i] = palette[k];
  }
  mapper.palette = palette; mapper.low = m.low; mapper.high = m.high;
  colour_bar.title = title(cs); colour_bar.visible = true;
  legend.text = `<span style="display:inline-block;width:12px;height:12px;` +
    `background:${no_value};margin:0 4px 0 10px"></span>no value`;
}
data['_colour'] = colours;
data['_x'] = position(xs);
data['_y'] = position(ys);
// the slice: every grid axis not drawn at its menu's value ('all': every value)
const keep = new Array(n).fill(true);
let held = [];
for (const menu of axis_menus) {
  const axis = menu.name.slice(3);
  if (axis == xs || axis == ys || menu.value == 'all') continue;
  const want = parseInt(menu.value), index = data[meta[axis].index];
  for (let i = 0; i < n; i++) if (index[i] != want) keep[i] = false;
  held.push(`${meta[axis].label} = ${meta[axis].values[want]}`);
}
in_slice.booleans = keep;
if (picked_row >= 0) {
  mark.data = Object.assign({}, mark.data, {_x: [data['_x'][picked_row]],
                                            _y: [data['_y'][picked_row]]});
}
source.change.emit();
chart.title.text = `${meta[cs].label} over ${meta[xs].label} and ${meta[ys].label}` +
  (held.length ? ` at ${held.join(', ')}` : '');
chart.below[0].axis_label = title(xs);
chart.left[0].axis_label = title(ys);
for (const [name, axis, ticker] of [[xs, chart.below[0], x_ticks], [ys, chart.left[0], y_ticks]]) {
  const mm = meta[name];
  if (mm.kind == 'category' && mm.axis) {
    ticker.ticks = mm.values.map((v, i) => i);
    const labels = {};
    mm.values.forEach((v, i) => { labels[i] = v; });
    axis.ticker = ticker; axis.major_label_overrides = labels;
  } else if (axis.ticker === ticker) {
    axis.major_label_overrides = {};
  }
}
"""

_JS_RANGES = """
const n = data['grid_point'].length, picked = [];
for (let i = 0; i < n; i++) {
  let inside = true;
  for (const slider of ranges) {
    const v = data[slider.name.slice(6)][i];
    const [low, high] = slider.value;
    if (!(v >= low && v <= high)) { inside = false; break; }
  }
  if (inside) picked.push(i);
}
source.selected.indices = picked;
"""

_JS_CHOSEN = """
const picked = source.selected.indices.slice().sort((a, b) => a - b);
const table = {};
for (const name of shown) { const c = data[name]; table[name] = picked.map(i => c[i]); }
chosen.data = table;
count.text = picked.length ?
  `<b>${picked.length.toLocaleString('en')}</b> designs selected` :
  'No design selected: brush a box or lasso on a panel, or narrow a range.';
"""

_JS_CSV = """
function cell(v) {
  if (typeof v == 'number') return Number.isFinite(v) ? String(v) : '';
  const s = String(v);
  return /[",\\n]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
}
const rows = [shown.map(name => cell(title(name))).join(',')];
const t = chosen.data, m = t['grid_point'] ? t['grid_point'].length : 0;
for (let i = 0; i < m; i++) rows.push(shown.map(name => cell(t[name][i])).join(','));
const blob = new Blob([rows.join('\\n') + '\\n'], {type: 'text/csv;charset=utf-8'});
const link = document.createElement('a');
link.href = URL.createObjectURL(blob);
link.download = 'selected_designs.csv';
document.body.appendChild(link); link.click(); link.remove();
"""
