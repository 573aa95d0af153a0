"""Chart text a designer reads (issue 61 item 1): every built-in example's design chart
(its own [chart] settings) and a front of two of its outputs are drawn, on a smaller grid
of the same axes; every label (axes, colour bars, legends, panel titles) is at most two
lines, and no text reaches outside the figure (matplotlib's extents of every visible text
after a draw). Short labels, never the long_name."""

import tomllib

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

import sweep
from sweep import example_specs, fronts
from sweep.charts import design_figure

AXIS_VALUES = 4  # per grid axis: the chart's layout, not its resolution, is under test


def small_example(name, values=AXIS_VALUES):
    """A built-in example's spec with every grid axis cut to ``values`` values."""
    document = tomllib.loads(example_specs.text(name))
    for axis, entry in document["grid"].items():
        if isinstance(entry, dict) and "num" in entry:
            entry["num"] = min(entry["num"], values)
        elif isinstance(entry, list):
            document["grid"][axis] = entry[:values]
    return document


def small(name):
    """The example's spec with every grid axis cut to AXIS_VALUES values, and its chart."""
    document = small_example(name)
    return document, document.pop("chart")


def labels(fig):
    """The label texts: axis and colour-bar labels, titles, legend entries."""
    out = []
    for ax in fig.axes:
        out += [ax.xaxis.label, ax.yaxis.label, ax.title]
        legend = ax.get_legend()
        if legend is not None:
            out += list(legend.get_texts())
    for legend in fig.legends:
        out += list(legend.get_texts())
    return [t.get_text() for t in out if t.get_visible() and t.get_text().strip()]


def assert_readable(fig, what):
    # matplotlib's own extent of everything drawn (tick labels outside the view are not)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    tight = fig.get_tightbbox(canvas.get_renderer())
    width, height = fig.get_size_inches()
    slack = 0.02  # inches: a glyph's antialiasing
    assert (tight.x0 >= -slack and tight.y0 >= -slack and tight.x1 <= width + slack
            and tight.y1 <= height + slack), (what, tight, (width, height))
    for text in labels(fig):
        assert text.count("\n") <= 1, (what, text)
        assert len(text) <= 90, (what, text)  # a label, not a long_name
    # what is drawn (at most two lines), then the atlas's title and the code's version
    title = fig.get_suptitle()
    assert title and title.count("\n") <= 3, (what, title)


def two_outputs(ds, chart):
    """Two numeric outputs with more than one finite value (the chart's own first)."""
    names = [chart.get("overlay"), chart["color"]] + [
        str(n) for n in ds.data_vars]
    picked = []
    for name in names:
        if not name or name in picked or name not in ds.data_vars:
            continue
        var = ds[name]
        if ("flag_meanings" in var.attrs or var.dtype.kind != "f"
                or set(var.dims) != set(ds.status.dims)):
            continue
        values = var.values[np.isfinite(var.values)]
        if np.unique(values).size > 1:
            picked.append(name)
        if len(picked) == 2:
            return picked
    return None


@pytest.mark.parametrize("name", example_specs.names())
def test_every_examples_chart_and_front_have_short_labels_inside_the_figure(name):
    document, chart = small(name)
    ds = sweep.run(document)
    # the chart's held values, at the nearest value of the smaller grid
    at = {axis: (float(ds[axis].sel({axis: value}, method="nearest")), "")
          for axis, value in chart.get("at", {}).items()}
    fig = design_figure(ds, chart["x"], chart["y"], chart["color"],
                        overlay=chart.get("overlay"), at=at or None)
    assert_readable(fig, f"{name} chart")
    objectives = two_outputs(ds, chart)
    assert objectives, name
    result = fronts.front(ds, maximize=objectives)
    assert_readable(fronts.figure(ds, result), f"{name} front")


def test_requirements_read_met_in_one_hue_failing_limits_in_warm_shades(tmp_path):
    """The limits example coloured by its requirements: met is blue, each failing limit a
    colour of its own, none of them met's, all warm (red above green and blue)."""
    from matplotlib.colors import to_rgb

    from sweep.charts import design_chart
    from sweep.palettes import MET_COLOUR

    document, chart = small("crank_rocker_limits")
    ds = sweep.run(document)
    drawn = design_chart(ds, chart["x"], chart["y"], "requirements", tmp_path / "r.png")
    colours = dict(zip(drawn.legend, drawn.legend_colours))
    assert to_rgb(colours["met"]) == to_rgb(MET_COLOUR)
    failing = {label: to_rgb(c) for label, c in colours.items()
               if label.startswith(("above", "below"))}
    assert failing and len(set(failing.values())) == len(failing)
    for label, (r, g, b) in failing.items():
        assert r > b and r > 0.5, (label, (r, g, b))


def test_a_signed_output_is_drawn_on_a_diverging_map_centred_on_zero():
    from matplotlib.colors import Normalize, TwoSlopeNorm

    document, chart = small("impact_machine")
    ds = sweep.run(document)
    values = ds.crank_impulse.values[np.isfinite(ds.crank_impulse.values)]
    assert values.min() < 0 < values.max()  # the example's crank impulse changes sign
    fig = design_figure(ds, chart["x"], chart["y"], "crank_impulse")
    norms = [image.norm for ax in fig.axes for image in ax.collections + ax.images
             if getattr(image, "norm", None) is not None and image.get_array() is not None]
    # the values' map centred on 0 (the blank cells' greys are categories of their own)
    centred = [n for n in norms if isinstance(n, TwoSlopeNorm)]
    assert centred and all(n.vcenter == 0.0 for n in centred)
    assert not [n for n in norms if type(n) is Normalize]


def test_a_chart_draws_into_the_users_axes_with_their_colour_map():
    """sweep.chart(..., ax=, cmap=, figsize=): the design chart in a panel of the user's
    own figure (the mesh on their axes, the colours of their map), or a new figure of
    their size; a wrong option is a UserError naming it."""
    import matplotlib
    from matplotlib.figure import Figure

    atlas = sweep.run({"mechanism": "crank_rocker",
                       "grid": {"R": [0.1, 0.2, 0.3], "largest_link": [2.0, 3.0, 4.0]}})
    fig = Figure()
    left, right = fig.subplots(1, 2)
    left.plot([0, 1], [0, 1])
    drawn = sweep.chart(atlas, "R", "largest_link", "impact_speed", ax=right, cmap="cividis")
    assert drawn is fig and right.collections and not left.collections
    meshes = [c for c in right.collections if hasattr(c, "get_cmap")]
    assert any(c.get_cmap().name == "cividis" for c in meshes)
    sized = sweep.chart(atlas, "R", "largest_link", "impact_speed", figsize=(5.0, 3.5))
    assert tuple(sized.get_size_inches()) == (5.0, 3.5)
    for kwargs, match in (({"cmap": "no_such_map"}, "cmap"), ({"ax": "left"}, "ax: a matplotlib"),
                          ({"figsize": (0, 3)}, "figsize"),
                          ({"ax": right, "figsize": (3, 3)}, "figsize")):
        with pytest.raises(sweep.UserError, match=match):
            sweep.chart(atlas, "R", "largest_link", "impact_speed", **kwargs)
    assert isinstance(matplotlib.colormaps["cividis"], matplotlib.colors.Colormap)
