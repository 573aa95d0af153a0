"""The explorer in a real browser (issue 61 items 3 and 5): the distribution's headless
Chromium with the network off opens the page of an atlas and of a front; no console error;
each view shows the designs numpy counts; a range brush selects, in every view and in the
table, exactly the designs an independent numpy filter picks, and the CSV download holds
them; hover on a known design shows its values; a menu changes the slice. A screenshot
of each page is kept in ``test-artifacts/``. The browser is installed by ``./tasks test``
(Debian's chromium and chromium-driver): without it these tests fail, they never skip."""

import csv
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import sweep
from tests.browser import CHROMEDRIVER, CHROMIUM, driver, errors, executable, ready
from tests.test_chart_text import small_example

ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    assert executable(CHROMIUM) and executable(CHROMEDRIVER), (
        "Debian's chromium and chromium-driver are needed: ./tasks test installs them")
    downloads = tmp_path_factory.mktemp("downloads")
    b = driver(downloads)
    b.downloads = downloads
    yield b
    b.quit()


def open_page(browser, page: Path, shot: str):
    browser.get(page.as_uri())
    ready(browser)
    ARTIFACTS.mkdir(exist_ok=True)
    time.sleep(0.5)  # the first frame drawn after the document is ready
    browser.save_screenshot(str(ARTIFACTS / f"{shot}.png"))
    assert errors(browser) == []


def flat(ds, name):
    """A variable as the page shows it, one value per grid point in C order (angles in
    degrees), by plain xarray."""
    var = ds[name].broadcast_like(ds.status).transpose(*ds.status.dims)
    values = var.values.ravel()
    if ds[name].attrs.get("units") == "rad":
        values = np.degrees(values)
    return values


def js(browser, code, *args):
    return browser.execute_script(code, *args)


@pytest.fixture(scope="module")
def limits(tmp_path_factory):
    folder = tmp_path_factory.mktemp("explore")
    document = small_example("crank_rocker_limits", 8)
    atlas = sweep.run(document, folder / "limits.nc")
    page = sweep.explore(atlas, folder / "limits.html")
    return xr.open_dataset(folder / "limits.nc"), page


def test_the_page_opens_offline_and_every_view_counts_the_designs(browser, limits):
    ds, page = limits
    text = page.read_text()
    assert "cdn.bokeh.org" not in text and "<script src=" not in text
    open_page(browser, page, "explorer_limits")
    n = ds.status.size
    assert js(browser, "return model('designs').data['grid_point'].length") == n
    # the slice: every grid axis not drawn (type) at its first value
    held = int(np.sum(np.broadcast_to(ds.type == ds.type[0], ds.status.shape)))
    drawn = len(js(browser, "return drawn('slice')"))
    assert drawn == held == n // ds.sizes["type"], (drawn, held)
    for name in js(browser, "return Bokeh.documents[0].all_models.size && "
                            "[...Bokeh.documents[0].all_models].map(m => m.name)"
                            ".filter(x => x && x.startsWith('points_'))"):
        assert len(js(browser, f"return drawn('{name}')")) == n, name


def test_a_menu_changes_the_slice(browser, limits):
    ds, page = limits
    open_page(browser, page, "explorer_limits_slice")
    js(browser, "model('at_type').value = '2'")
    time.sleep(0.3)
    drawn = js(browser, "return drawn('slice')")
    kinds = flat(ds, "type")
    assert sorted(drawn) == np.flatnonzero(kinds == str(ds.type.values[2])).tolist()
    assert "type = c" in js(browser, "return model('slice_plot').title.text")
    js(browser, "model('at_type').value = 'all'")
    time.sleep(0.3)
    assert len(js(browser, "return drawn('slice')")) \
        == ds.status.size


def test_a_range_brush_selects_what_numpy_selects_in_every_view_table_and_csv(
        browser, limits):
    ds, page = limits
    open_page(browser, page, "explorer_limits_brush")
    names = js(browser, "return [...Bokeh.documents[0].all_models].map(m => m.name)"
                        ".filter(x => x && x.startsWith('range_')).map(x => x.slice(6))")
    assert len(names) >= 2
    mask = np.ones(ds.status.size, bool)
    for name in names[:2]:
        values = flat(ds, name)
        low, high = (float(v) for v in np.nanquantile(values, [0.3, 0.8]))
        js(browser, f"model('range_{name}').value = [{low!r}, {high!r}]")
        mask &= (values >= low) & (values <= high)
    time.sleep(0.3)
    expected = np.flatnonzero(mask).tolist()
    assert 0 < len(expected) < ds.status.size
    assert sorted(js(browser, "return model('designs').selected.indices")) == expected
    assert js(browser, "return model('chosen').data['grid_point']") == expected
    assert js(browser, "return Bokeh.index.find_one(model('table')).data.getLength()") \
        == len(expected)
    assert f"{len(expected):,}" in js(browser, "return model('count').text")
    # the download: every selected design, its values as the atlas has them
    before = set(browser.downloads.iterdir())
    js(browser, "deep('button').find(b => b.textContent.includes('CSV')).click()")
    for _ in range(100):
        new = [p for p in set(browser.downloads.iterdir()) - before
               if p.suffix == ".csv"]
        if new:
            break
        time.sleep(0.1)
    assert new, "no CSV downloaded"
    rows = list(csv.reader(new[0].open()))
    assert rows[0][0] == "grid point"
    assert [int(r[0]) for r in rows[1:]] == expected
    header = rows[0]
    column = next(i for i, h in enumerate(header) if h.startswith("blow energy"))
    shown = np.array([float(r[column]) if r[column] else np.nan for r in rows[1:]])
    np.testing.assert_array_equal(shown, flat(ds, "blow_energy")[expected])


def test_hover_on_a_known_design_shows_its_values(browser, limits):
    ds, page = limits
    open_page(browser, page, "explorer_limits_hover")
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    drawn = js(browser, "return drawn('slice')")
    energy = flat(ds, "blow_energy")
    point = next(i for i in drawn if np.isfinite(energy[i]))
    x, y = js(browser, """
        const v = Bokeh.index.find_one(model('slice_plot'));
        const d = model('designs').data, r = v.el.getBoundingClientRect();
        return [r.left + v.frame.x_scale.compute(d['_x'][arguments[0]]),
                r.top + v.frame.y_scale.compute(d['_y'][arguments[0]])];""", point)
    actions = ActionBuilder(browser)
    actions.pointer_action.move_to_location(int(round(x)), int(round(y)))
    actions.perform()
    ActionChains(browser).pause(0.5).perform()
    text = " ".join(js(browser, "return deep('.bk-tooltip-content, .bk-Tooltip')"
                                ".map(e => e.innerText || e.textContent)"))
    assert f"{energy[point]:.6g}" in text, (point, text[:300])
    assert f"{int(point)}" in text
    ARTIFACTS.mkdir(exist_ok=True)
    browser.save_screenshot(str(ARTIFACTS / "explorer_limits_hover.png"))


def test_a_fronts_page_marks_the_picked_design(browser, tmp_path):
    document = small_example("crank_rocker_limits", 12)
    atlas = sweep.run(document)
    front = sweep.pareto(atlas, maximize="blow_rate", minimize="transmission_angle_opposite",
                         path=tmp_path / "front.nc")
    page = sweep.explore(tmp_path / "front.nc", tmp_path / "front.html")
    open_page(browser, page, "explorer_front")
    picked = np.flatnonzero(front.designs.picked.values == 1).tolist()
    assert len(picked) == 1
    assert js(browser, "return model('picked').data['grid_point']") == picked
    matrix = js(browser, "return [...Bokeh.documents[0].all_models].map(m => m.name)"
                         ".filter(x => x && x.startsWith('range_')).map(x => x.slice(6))")
    assert matrix[:2] == ["blow_rate", "transmission_angle_opposite"]
    size = front.designs.sizes["design"]
    assert size > 1 and len(js(browser, "return drawn('slice')")) == size  # the whole front


@pytest.mark.slow
@pytest.mark.parametrize("name", list(sweep.examples()))
def test_every_examples_explorer_opens_offline_with_every_design(browser, tmp_path, name):
    atlas = sweep.run(small_example(name, 4))
    page = sweep.explore(atlas, tmp_path / f"{name}.html")
    open_page(browser, page, f"explorer_{name}")
    n = atlas.status.size
    assert js(browser, "return model('designs').data['grid_point'].length") == n
    # the chart's slice: the grid axes not drawn at their first value (every value where
    # the chart is of outputs), counted by numpy on the atlas's own axes
    x, y = js(browser, "return [model('x_menu').value, model('y_menu').value]")
    dims = list(atlas.status.dims)
    held = [d for d in dims if d not in (x, y)] if x in dims and y in dims else []
    expected = n // int(np.prod([atlas.sizes[d] for d in held])) if held else n
    assert len(js(browser, "return drawn('slice')")) == expected
    for panel in js(browser, "return [...Bokeh.documents[0].all_models].map(m => m.name)"
                             ".filter(x => x && x.startsWith('points_'))"):
        assert len(js(browser, f"return drawn('{panel}')")) == n, panel


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, limits):
    ds, page = limits
    atlas = Path(ds.encoding["source"])
    for kwargs, match in (({"variables": "nope,blow_rate"}, "variables: 'nope'"),
                          ({"variables": "blow_rate"}, "variables: give 2 to 4"),
                          ({"max_designs": 0}, "max_designs")):
        with pytest.raises(sweep.UserError, match=match):
            sweep.explore(atlas, tmp_path / "x.html", **kwargs)
    with pytest.raises(sweep.UserError, match="exists"):
        sweep.explore(atlas, page)
    with pytest.raises(sweep.UserError, match=r"must end in \.html"):
        sweep.explore(atlas, atlas, force=True)
    assert not (tmp_path / "x.html").exists()


def test_beyond_its_limit_the_page_shows_every_kth_design_and_says_so(limits, tmp_path):
    ds, _ = limits
    page = sweep.explore(Path(ds.encoding["source"]), tmp_path / "few.html",
                         max_designs=50)
    text = page.read_text()
    step = -(-ds.status.size // 50)
    shown = len(range(0, ds.status.size, step))
    assert (f"{shown:,} of {ds.status.size:,} designs: one in every {step}, in grid order "
            "(the page shows at most 50;") in text
