"""One declaration per mechanism, options by name, no import cycles: the contracts between
sweep/ and kernels/ (docs/architecture.md)."""

import ast
import json
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from sweep import engine, registry, runner, spec
from sweep.cli import main
from tests.conftest import flag_words

ROOT = Path(__file__).resolve().parent.parent
TOY = '''
mechanism = "toy"
[grid]
radius = [0.1, 0.2, 0.3]
side = ["near", "far"]
[fixed]
omega1 = -20.0
[method]
scale = 2.0
'''


def _status_names_used(module_file: Path) -> set[str]:
    tree = ast.parse(module_file.read_text())
    return {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name) and node.value.id == "S"}


@pytest.mark.parametrize("name", registry.names())
def test_each_kernel_emits_exactly_the_statuses_it_declares(name):
    """S = DECLARATION.status_codes: a kernel can only write a declared status (any other
    name is an AttributeError), and every declared one is written somewhere."""
    kernel = registry.get(name)
    path = Path(__import__(registry.MECHANISMS[name], fromlist=["x"]).__file__)
    assert _status_names_used(path) == set(kernel.declaration.status)


#: names a literal index may follow in kernels/: vectors and arrays of the numerics, where
#: index 0 and 1 are components of one quantity, not fields of a record: states and their
#: derivatives (y, dy, f, s, ...), 2-vectors and row-major 2 x 2 matrices of the section
#: map's accelerators, coefficient arrays, an array's first or last element, the tangent's
#: 3 x 3 block, RK stages; and Python lists in a declaration's messages. A record (the
#: machine's data, a linkage point, a method's options, a node) is read by name.
VECTORS = {
    "y", "y0", "y1", "dy", "f", "f0", "f1", "s", "s1", "ds", "x", "x0", "x1", "v", "to",
    "step", "fixed", "x_from", "x_secant", "jac", "a", "b", "c", "d", "key", "here",
    "canonical", "history", "half", "ap", "av", "aw", "k1", "k2", "k3", "k4", "ks",
    "coefficients", "args", "types", "mean", "largest", "values", "order", "front",
    "impacts", "mag", "real", "nonzero", "below", "gam", "zr", "zi", "ir", "ii", "jr", "ji",
    "nr", "ni", "dr", "di", "missing", "extra", "status"}


def literal_indices(path: Path) -> list[str]:
    """``name[<literal>]`` in a file's code (comments and strings left out), for every name
    outside VECTORS and every attribute but ``shape``, each as "file:line: code"."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Subscript):
            continue
        index = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
        if not any(isinstance(i, ast.Constant) and isinstance(i.value, int)
                   or isinstance(i, ast.UnaryOp) and isinstance(i.operand, ast.Constant)
                   for i in index):
            continue
        value = node.value
        name = value.id if isinstance(value, ast.Name) else \
            value.attr if isinstance(value, ast.Attribute) else None
        if name is not None and name not in VECTORS and name != "shape":
            found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_literal_slot_index_in_kernels(tmp_path):
    """Records are read by name: no literal index into a record anywhere in kernels/ (the
    machine's 33-slot tuple read as m[0] ... m[30] failed this). A planted read fails it."""
    hits = [hit for path in sorted((ROOT / "kernels").rglob("*.py"))
            for hit in literal_indices(path)]
    assert not hits, hits
    planted = tmp_path / "planted.py"
    planted.write_text("def f(m, nd, y, a):\n    return m[3] + nd[0] + y[1] + a.shape[1]\n")
    assert len(literal_indices(planted)) == 2


def _imports(path: Path, package: str) -> set[str]:
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            found |= {n for n in names if n.startswith(package + ".")}
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith(package + ".")}
    return found


def import_cycles(package: str) -> dict:
    """The modules of a package (its subpackages included) that reach themselves through
    the package's own imports (lazy ones included), with what each imports."""
    modules = {".".join(p.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__"): p
               for p in (ROOT / package).rglob("*.py")}
    graph = {m: {i for i in _imports(p, package) if i in modules and i != m}
             for m, p in modules.items()}

    def reach(start):
        seen, todo = set(), [start]
        while todo:
            for nxt in graph[todo.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    return {m: graph[m] for m in graph if m in reach(m)}


@pytest.mark.parametrize("package", ["sweep", "kernels"])
def test_each_package_imports_without_cycles(package):
    """The package imports only downward: no module reaches itself through imports."""
    assert import_cycles(package) == {}


def owned_modules(architecture: str) -> set[str]:
    """The module paths that docs/architecture.md's table "Who owns what" names: a row's
    first cell holds paths (``kernels/pendulum/tools.py``), file names of the last path's
    folder (``blade.py``), or a folder (``kernels/impact/``: its ``__init__.py``) whose
    other modules the second cell names (``runge_kutta``)."""
    table = architecture.split("## Who owns what", 1)[1].split("\n## ", 1)[0]
    named = set()
    for row in table.splitlines():
        cells = row.split("|")
        if len(cells) < 4 or not cells[1].strip().startswith("`"):
            continue
        folder = ""
        for token in re.findall(r"`([^`]+)`", cells[1]):
            if token.endswith("/"):
                named |= {token + stem + ".py"
                          for stem in ["__init__", *re.findall(r"`(\w+)`", cells[2])]}
            elif "/" in token:
                folder = token.rsplit("/", 1)[0] + "/"
                named.add(token)
            else:
                named.add(folder + token)
    return named


def test_the_ownership_table_names_every_module():
    """docs/architecture.md's table names every module of both packages (their
    ``__init__.py`` files that define nothing apart). A module added without its row, or a
    row left behind by a module that went, fails it."""
    modules = {str(p.relative_to(ROOT)) for package in ("sweep", "kernels")
               for p in (ROOT / package).rglob("*.py")
               if p.name != "__init__.py" or len(p.read_text().splitlines()) > 10}
    named = owned_modules((ROOT / "docs" / "architecture.md").read_text())
    assert modules - named == set(), "modules without a row"
    assert {m for m in named if m.endswith(".py")} - modules == set(), "rows without a module"
    planted = ("## Who owns what\n| module | owns |\n|---|---|\n"
               "| `kernels/pendulum/tools.py`, `blade.py` | tools |\n"
               "| `kernels/impact/` | the core: `flight`, `events` |\n")
    assert owned_modules(planted) == {"kernels/pendulum/tools.py", "kernels/pendulum/blade.py",
                                      "kernels/impact/__init__.py", "kernels/impact/flight.py",
                                      "kernels/impact/events.py"}


def test_a_toy_mechanism_needs_one_declaration_one_kernel_and_one_registry_line(
        tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(registry.MECHANISMS, "toy", "tests.toy_mechanism")
    s = spec.parse(TOY)  # validated against its declaration
    runner.run_sweep(s, tmp_path / "toy.nc", progress=False, history="toy")
    ds = xr.open_dataset(tmp_path / "toy.nc")
    np.testing.assert_allclose(ds["tip_speed"].sel(side="far").values,
                               [4.0, 8.0, 12.0], rtol=1e-15)  # |omega1| r scale
    assert ds["tip_speed"].attrs["units"] == "m s-1" and ds["radius"].attrs["units"] == "m"
    assert ds["side_used"].dtype == np.int8
    assert list(flag_words(ds["side_used"]).ravel()) == ["near", "far"] * 3
    assert json.loads(ds.attrs["method"])["scale"] == 2.0
    with pytest.raises(Exception, match="fixed.omega1"):
        spec.parse(TOY.replace("omega1 = -20.0", "omega1 = 0.0"))
    with pytest.raises(SystemExit) as e:
        main(["parameters"])
    assert e.value.code == 0 and "toy" in capsys.readouterr().out
    with pytest.raises(SystemExit) as e:
        main(["parameters", "toy"])
    text = capsys.readouterr().out
    assert e.value.code == 0 and "radius" in text and "[m]" in text and "tip_speed" in text


def test_method_options_reach_the_kernel_by_name_and_are_words_in_the_atlas(monkeypatch):
    seen = []
    s = spec.parse('mechanism = "rotary_pendulum"\n[grid]\nk = [1.5, 2.5]\n'
                   'omega1 = [20.0, 40.0]\n[method]\nintegrator = "dopri5"\nrtol = 1e-7')
    real = s.kernel

    def spy(params, method):
        seen.append((params[s.mechanism.parameter_index.omega1].copy(), method))
        return real(params, method)

    s.kernel = spy
    ds = engine.build(s).compute()
    omega, method = seen[0]
    assert set(omega) == {20.0, 40.0}
    assert method.rtol == 1e-7 and method.integrator == s.mechanism.method_key(
        "integrator").choices["dopri5"]
    recorded = json.loads(ds.attrs["method"])
    assert recorded["integrator"] == "dopri5" and recorded["rtol"] == 1e-7
    assert json.loads(ds.attrs["spec"])["method"]["integrator"] == "dopri5"


def test_flag_outputs_are_small_integers_with_their_meanings(tmp_path):
    s = spec.parse('mechanism = "crank_rocker"\n[grid]\nR = [0.3]\n'
                   'largest_link = [1.5, 3.0, 30.0]\ntype = ["a", "b"]')
    runner.run_sweep(s, tmp_path / "cr.nc", progress=False, history="test")
    ds = xr.open_dataset(tmp_path / "cr.nc")
    for name in ("crank_turns_fully", "assembly_branch", "status"):
        assert ds[name].dtype == np.int8 and "_FillValue" not in ds[name].encoding
    turns = flag_words(ds["crank_turns_fully"])[0]
    branch = flag_words(ds["assembly_branch"])[0]
    # type a at 1.5 < gamma: no full turn; type b at 1.5 and 3: no real synthesis
    assert list(turns[:, 0]) == ["no", "yes", "yes"]
    assert list(turns[:, 1]) == ["undetermined", "undetermined", "yes"]
    assert list(branch[:, 0]) == ["undetermined", "minus", "minus"]
    assert branch[2, 1] == "plus"  # type b strikes on sigma = +1 for omega1 > 0


#: what each mechanism needs besides the swept parameter, and per parameter what it needs
BASES = {"crank_rocker": dict(largest_link=3.0)}
NEEDS = {
    ("crank_rocker", "largest_link"): dict(),
    ("crank_rocker", "lambda0"): dict(type="general", lambda2=3.0, lambda3=2.0,
                                      largest_link=None),
    ("crank_rocker", "lambda2"): dict(type="general", lambda0=2.0, lambda3=2.0,
                                      largest_link=None),
    ("crank_rocker", "lambda3"): dict(type="general", lambda0=2.0, lambda2=3.0,
                                      largest_link=None),
    ("crank_rocker", "base_root"): dict(type="b", largest_link=14.0),
    ("rotary_pendulum", "kappa"): dict(model="rigid"),
    ("rotary_pendulum", "tool_window"): dict(model="rigid", kappa=1.2, k=1.0,
                                             tool="lab_window"),
    **{("rotary_pendulum", name): dict(model="rotor", kappa=1.2, k=1.0)
       for name in ("rotor_inertia_ratio", "motor_slope", "idle_speed")},
    **{("linkage_forces", name): dict(base_motion="rotating")
       for name in ("base_omega", "base_epsilon", "crank_pivot_x", "crank_pivot_y")},
    **{("linkage_forces", name): dict(base_motion="harmonic")
       for name in ("base_amplitude", "base_frequency_ratio", "base_phase")},
    ("impact_machine", "base_root"): dict(type="b", largest_link=14.0),
    **{("impact_machine", name): dict(type="general", lambda0=2.029159519725557,
                                      lambda2=2.5, lambda3=1.470840480274443)
       for name in ("lambda0", "lambda2", "lambda3")},
}
VALUES = {("crank_rocker", "lambda0"): [2.0, 2.5], ("crank_rocker", "lambda2"): [3.0, 2.5],
          ("crank_rocker", "lambda3"): [2.0, 1.5], ("crank_rocker", "largest_link"): [3.0, 4.0],
          ("crank_rocker", "envelope"): [0.5, 0.6],
          ("crank_rocker", "impact_speed_limit"): [8.0, 10.0],
          ("rotary_pendulum", "kappa"): [1.2, 1.5],
          ("impact_machine", "lambda0"): [2.029159519725557, 2.2],
          ("impact_machine", "design_restitution"): [0.3, 0.35],
          ("impact_machine", "lambda2"): [2.5, 2.6], ("impact_machine", "lambda3"):
          [1.470840480274443, 1.4]}


def _two_values(mechanism, p):
    if (mechanism, p.name) in VALUES:
        return VALUES[mechanism, p.name]
    if p.choices is not None:
        return list(p.choices)[:2]
    d = p.default
    if d:
        return [d, d * 1.1]
    return [0.0, 0.1] if p.minimum == 0.0 and p.min_inclusive else [1.0, 1.1]


@pytest.mark.slow
@pytest.mark.parametrize("mechanism", registry.names())
def test_every_parameter_of_every_mechanism_can_be_swept(mechanism):
    """Each parameter on the grid, through the engine to a Dataset: its coordinate carries
    its values and every output is a variable, except one that only echoes a grid axis
    (crank_rocker's lambdas: they once collided with the axis, issue 12) and the ones
    computed only on request (absent unless the spec lists them)."""
    mech = registry.get(mechanism).declaration
    for p in mech.parameters:
        fixed = dict(BASES.get(mechanism, {}))
        fixed.update(NEEDS.get((mechanism, p.name), {}))
        fixed = {k: v for k, v in fixed.items() if v is not None and k != p.name}
        raw = {"mechanism": mechanism, "grid": {p.name: _two_values(mechanism, p)},
               "fixed": fixed}
        s = spec.validate(raw)
        ds = engine.build(s).compute()
        given = raw["grid"][p.name]  # numbers become an increasing axis, categories stay
        assert list(ds[p.name].values) == ([str(v) for v in given] if p.choices else
                                           sorted(float(v) for v in given)), p.name
        for o in mech.outputs:
            if o.on_request:
                assert o.name not in ds.data_vars, (p.name, o.name)
                continue
            assert o.name in ds.data_vars or o.echoes == p.name, (p.name, o.name)
        echo = [o.name for o in mech.outputs if o.echoes == p.name]
        for name in echo:  # the echo equals the axis: nothing is lost by dropping it
            values = s.kernel(engine.block_parameters(s, [(0, 2)]), s.method_record)[0]
            row = getattr(mech.output_index, name)
            np.testing.assert_array_equal(values[row], ds[p.name].values)
