"""The design sheet (issue 61 item 4): one page for one design whose every value is the
atlas's at that grid point (read back from the page and compared with plain xarray), whose
requirement verdicts are an independent check of the limits, with the design's profiles and
its place on a front; printed to a PDF by the distribution's Chromium, and opened in it
with no console error. Bad input is one line and writes nothing."""

import json
import re
from html.parser import HTMLParser

import numpy as np
import pytest
import xarray as xr

import sweep
from tests.browser import driver, errors, ready  # noqa: F401  (ready: a Bokeh page's)
from tests.command_line import run_cli
from tests.test_chart_text import small_example


class Tables(HTMLParser):
    """The page's tables as lists of rows of cell texts, and its images."""

    def __init__(self):
        super().__init__()
        self.tables, self.images, self._cell = [], [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = ""
        elif tag == "img":
            self.images.append(dict(attrs).get("alt", ""))

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[-1][-1].append(" ".join(self._cell.split()))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data


def read(page):
    parser = Tables()
    parser.feed(page.read_text())
    return parser


@pytest.fixture(scope="module")
def forces(tmp_path_factory):
    """linkage_forces with profiles, and a crank_rocker atlas with requirements."""
    folder = tmp_path_factory.mktemp("sheet")
    sweep.run({"mechanism": "linkage_forces",
               "grid": {"omega1": [20.0, 35.0], "tilt": [0.1, 0.4, 0.9]},
               "method": {"profile_points": 73}}, folder / "lf.nc")
    sweep.run(small_example("crank_rocker_limits", 8), folder / "limits.nc")
    return folder


def test_every_value_on_the_sheet_is_the_atlases_at_that_design(forces, tmp_path):
    atlas = xr.open_dataset(forces / "lf.nc")
    rng = np.random.default_rng(61)
    design = int(rng.integers(atlas.status.size))
    page, pdf = sweep.sheet(forces / "lf.nc", tmp_path / "s.html", design=design)
    tables = read(page)
    at = dict(zip(atlas.status.dims, np.unravel_index(design, atlas.status.shape)))
    point = atlas.isel(at)
    rows = {row[0]: row for table in tables.tables for row in table[1:]}
    checked = 0
    for name, var in point.data_vars.items():
        if var.ndim or "flag_meanings" in var.attrs:
            continue
        value = float(var.values)
        if atlas[name].attrs.get("units") == "rad":
            value = np.degrees(value)
        assert rows[name][2] == f"{value:.6g}", name
        checked += 1
    assert checked >= 7
    for axis in atlas.status.dims:
        assert rows[axis][2] == f"{float(point[axis]):.6g}" or \
            rows[axis][2] == f"{np.degrees(float(point[axis])):.6g}"
    assert rows["l1"][2] == f"{json.loads(atlas.attrs['spec'])['fixed']['l1']:.6g}"
    assert "profiles of this design over the cycle" in tables.images
    assert pdf is not None and pdf.read_bytes()[:5] == b"%PDF-"


def test_requirement_verdicts_and_margins_are_the_limits(forces, tmp_path):
    atlas = xr.open_dataset(forces / "limits.nc")
    limits = json.loads(atlas.attrs["spec"])["requirements"]
    usable = np.flatnonzero(atlas.status.values.ravel() == 0)
    for design in usable[:: max(1, usable.size // 5)]:
        page, _ = sweep.sheet(atlas, tmp_path / f"d{design}.html", design=int(design),
                              pdf=False)
        table = next(t for t in read(page).tables if t[0][0] == "limit")
        point = atlas.isel(dict(zip(atlas.status.dims,
                                    np.unravel_index(design, atlas.status.shape))))
        for row in table[1:]:
            name = row[0].split()[0]
            number = float(re.match(r"[<>=]+\s*([-+0-9.eE]+)", limits[name]).group(1))
            value = float(point[name])
            if "deg" in limits[name]:
                number = np.radians(number)
            holds = value >= number  # both limits of the example are lower limits
            assert row[3] == ("met" if holds else "fails"), (design, row)
            assert (float(row[2].rstrip("%")) >= 0) == holds


def test_pareto_writes_the_picked_designs_sheet_with_its_front(forces, tmp_path, capsys):
    code, out, err = run_cli(capsys, "pareto", forces / "limits.nc", "--max", "blow_rate",
                             "--min", "envelope", "--sheet", tmp_path / "pick.html")
    assert code == 0, err
    assert "sheet: " in out and "pdf: " in out
    tables = read(tmp_path / "pick.html")
    assert "the front with this design marked" in tables.images
    rows = {row[0]: row for table in tables.tables for row in table[1:]}
    assert rows["picked"][2] == "yes"
    assert (tmp_path / "pick.pdf").read_bytes()[:5] == b"%PDF-"


def test_the_sheet_opens_offline_in_chromium_with_no_console_error(forces, tmp_path):
    page, _ = sweep.sheet(forces / "lf.nc", tmp_path / "s.html", where="omega1 > 30",
                          pdf=False)
    browser = driver()
    try:
        browser.get(page.as_uri())
        assert browser.execute_script("return document.images.length") >= 1
        assert browser.execute_script(
            "return [...document.images].every(i => i.complete && i.naturalWidth > 0)")
        assert errors(browser) == []
    finally:
        browser.quit()


def test_bad_input_is_one_line_exit_2_and_writes_nothing(forces, tmp_path, capsys):
    atlas = forces / "lf.nc"
    for kwargs, match in (({}, "design: give one of"),
                          ({"design": 1, "where": "omega1 > 0"}, "design: give one of"),
                          ({"design": 10**6}, "design: a grid point's index"),
                          ({"design": -1}, "design: a grid point's index"),
                          ({"where": "omega1 > 1e9"}, "where: no grid point matches"),
                          ({"where": "nope > 1"}, "nope")):
        with pytest.raises(sweep.UserError, match=match):
            sweep.sheet(atlas, tmp_path / "x.html", **kwargs)
    for args in (["sheet", atlas, "--design", "99999", "-o", tmp_path / "x.html"],
                 ["sheet", atlas, "--design", "0", "-o", atlas],
                 ["sheet", tmp_path / "missing.nc", "--design", "0", "-o",
                  tmp_path / "x.html"],
                 ["explore", atlas, "-o", tmp_path / "x.html", "--vars", "nope,omega1"]):
        code, out, err = run_cli(capsys, *args)
        assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, (args, err)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
@pytest.mark.parametrize("name", list(sweep.examples()))
def test_every_examples_sheet_holds_its_outputs_and_status(name, tmp_path):
    from tests.test_chart_text import small

    document, _ = small(name)
    atlas = sweep.run(document, tmp_path / f"{name}.nc")
    words = sweep.decode(atlas).status.values.ravel()
    usable = np.flatnonzero(np.isin(words, ["ok", "special_position",
                                            "second_special_position"]))
    design = int(usable[0]) if usable.size else 0
    page, _ = sweep.sheet(tmp_path / f"{name}.nc", tmp_path / f"{name}.html",
                          design=design, pdf=False)
    rows = {row[0]: row for table in read(page).tables for row in table[1:]}
    assert rows["status"][2] == str(words[design])
    assert set(document.get("outputs", [])) <= set(rows)
