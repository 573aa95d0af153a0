"""linkage_forces through the engine: spec boundary, profiles in the atlas, invariance."""

import numpy as np
import pytest
import xarray as xr

from sweep import runner, spec
from sweep.cli import main
from sweep.errors import UserError

SPEC = '''
mechanism = "linkage_forces"
[grid]
omega1 = [10.0, 30.0, -20.0]
tilt = {start = 0.0, stop = 1.0, num = 3}
m3 = [4.0, 8.0]
[method]
profile_points = 36
quadrature_points = 64
peak_samples = 181
'''


def write(tmp_path, name, chunk=None, workers=None, text=SPEC):
    s = spec.parse(text)
    runner.run_sweep(s, tmp_path / name, chunk=chunk, progress=False, workers=workers,
                       history="test")
    return xr.open_dataset(tmp_path / name)


@pytest.mark.parametrize("text, key", [
    ("[fixed]\nm2 = -1.0", "fixed.m2"),
    ("[fixed]\nJ1 = -0.1", "fixed.J1"),
    ("[fixed]\nl2 = 0.0", "fixed.l2"),
    ("[fixed]\nl0 = -0.2", "fixed.l0"),
    ("[fixed]\ng = nan", "fixed.g"),
    ("[fixed]\nbase_omega = 2.0", "base_omega"),
    ("[method]\nquadrature_points = 20.5", "method.quadrature_points"),
    ("[method]\nspecial_window = 0.0", "method.special_window"),
    ("[method]\nprofile_points = -3", "method.profile_points"),
    ('outputs = ["F21_n"]', "profile_points"),
    ("[fixed]\ntilt = 7.0", "fixed.tilt"),
])
def test_bad_kinetostatics_specs_are_rejected(text, key):
    head, _, rest = text.partition("\n") if text.startswith("outputs") else ("", "", text)
    full = (head + "\n" if head else "") + 'mechanism = "linkage_forces"\n[grid]\nomega1 = [30.0]\n' + rest
    with pytest.raises(UserError) as err:
        spec.parse(full)
    assert key in str(err.value) and "\n" not in str(err.value)


def test_profiles_become_an_atlas_dimension_with_cf_attributes(tmp_path):
    ds = write(tmp_path, "a.nc")
    assert ds["F21_n"].dims == ("omega1", "tilt", "m3", "crank_angle")
    assert ds["force_peak_B"].dims == ("omega1", "tilt", "m3")
    assert ds["crank_angle"].attrs["units"] == "rad" and ds.sizes["crank_angle"] == 36
    for name in list(ds.data_vars) + list(ds.coords):
        assert ds[name].attrs.get("units") and ds[name].attrs.get("long_name"), name
    meanings = ds["status"].attrs["flag_meanings"].split()
    code = ds["status"].attrs["flag_values"][meanings.index("special_position")]
    assert set(ds["status"].values.ravel()) == {code}
    # the peak is at least every profile sample outside the window
    peak = ds["force_peak_B"].isel(omega1=1, tilt=1, m3=1).item()
    f21 = np.hypot(ds["F21_n"], ds["F21_t"]).isel(omega1=1, tilt=1, m3=1).values
    angles = ds["crank_angle"].values
    outside = (angles > 0.01) & (angles < 2 * np.pi - 0.01)
    assert peak >= f21[outside].max() * (1 - 1e-9)
    # heavier rocker, larger reactions at D; the drive's cycle work scales with speed^2
    d = ds["force_peak_D"].isel(omega1=1, tilt=0)
    assert d.sel(m3=8.0) > d.sel(m3=4.0)
    w = ds["cycle_work"].isel(tilt=0, m3=1)
    assert w.sel(omega1=30.0) / w.sel(omega1=10.0) == pytest.approx(9.0, rel=1e-6)
    assert (ds["cycle_work"] > 0).all()  # energy lost at impact, either rotation direction


def test_profiles_are_chunk_and_thread_invariant(tmp_path):
    a = write(tmp_path, "a.nc", chunk=1, workers=2)
    b = write(tmp_path, "b.nc", chunk=10**6, workers=1)
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name


def test_profile_chart_cli(tmp_path, capsys):
    write(tmp_path, "a.nc")
    png = tmp_path / "p.png"
    with pytest.raises(SystemExit) as e:
        main(["profile", str(tmp_path / "a.nc"), "--vars", "F21_n,balancing_moment",
              "--where", "omega1 == 30 and m3 == 8", "-o", str(png)])
    assert e.value.code == 0 and png.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(SystemExit) as e:
        main(["profile", str(tmp_path / "a.nc"), "--vars", "force_peak_B", "-o", str(png),
              "--force"])
    assert e.value.code == 2 and "not a profile" in capsys.readouterr().err


def test_six_link_atlas_with_rocker_profile_over_4pi(tmp_path):
    text = '''
mechanism = "six_link"
[grid]
beta = {start = -1.0, stop = 1.0, num = 5}
mu5 = [2.5, 4.0]
[method]
profile_points = 64
samples = 720
'''
    ds = write(tmp_path, "s.nc", text=text)
    assert ds["rocker_angle"].dims == ("beta", "mu5", "crank_angle")
    assert ds["crank_angle"].values.max() < 4 * np.pi
    assert (ds["status"] == 0).all()
    zero = ds.sel(beta=0.0)
    np.testing.assert_allclose(zero["transfer_impact_1"], zero["transfer_impact_2"], atol=1e-8)
    with pytest.raises(UserError, match="fixed.direction"):
        spec.parse('mechanism = "six_link"\n[grid]\nbeta = [0.0]\n[fixed]\ndirection = 2')


def test_spring_balancer_atlas_and_method_keys(tmp_path, monkeypatch):
    import kernels.balancer as bl

    calls = []
    real = bl.fourier_coefficients

    def counting(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(bl, "fourier_coefficients", counting)
    text = '''
mechanism = "spring_balancer"
[grid]
f = {start = 0.5, stop = 1.5, num = 11}
r = [0.5, 1.0, 1.6]
lambda3 = [2.5, 3.5]
[method]
harmonics = "auto"
'''
    ds = write(tmp_path, "b.nc", text=text, chunk=10**6)
    # once per geometry, not once per grid point (66 points), and once for the run's
    # compile-first sample point (engine.warm_up: one point, the first geometry)
    assert len(calls) == 3 and calls[0] == calls[1]
    meanings = ds["status"].attrs["flag_meanings"].split()
    codes = dict(zip(meanings, ds["status"].attrs["flag_values"]))
    # both (3, 1, 3.5, 2.5) and (3, 1, 3.5, 3.5) are crank-rockers
    assert set(np.unique(ds["status"].values)) <= {codes["ok"], codes["resonance"]}
    assert ds["swing"].sel(lambda3=2.5).isel(f=0, r=0).item() == pytest.approx(0.983338018,
                                                                               abs=1e-9)
    assert '"harmonics": "auto"' in ds.attrs["spec"]
    with pytest.raises(UserError, match="method.harmonics"):
        spec.parse('mechanism = "spring_balancer"\n[grid]\nf = [1.0]\n[method]\nharmonics = "many"')
    with pytest.raises(UserError, match="fixed.eta"):
        spec.parse('mechanism = "spring_balancer"\n[grid]\nf = [1.0]\n[fixed]\neta = -0.1')
    s = spec.parse('mechanism = "spring_balancer"\n[grid]\nf = [1.0]\n[method]\nharmonics = 12')
    assert s.method["harmonics"] == 12.0


def test_spring_balancer_rejects_a_geometry_that_is_not_a_crank_rocker(tmp_path):
    text = '''
mechanism = "spring_balancer"
[grid]
f = [1.0]
lambda2 = [3.5, 1.2]
'''
    ds = write(tmp_path, "c.nc", text=text)
    meanings = ds["status"].attrs["flag_meanings"].split()
    codes = dict(zip(meanings, ds["status"].attrs["flag_values"]))
    assert ds["status"].sel(lambda2=1.2).item() == codes["not_assemblable"]
    assert np.isnan(ds["swing"].sel(lambda2=1.2).item())
