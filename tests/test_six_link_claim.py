"""[SIX]'s claim as numbers (issue 64 item 2): the chains between the single impact four-bar
and the six-link built on it, both ways, at the same striker linkage and the same mean
energy per blow, checked against what each source gives independently: the blows' energy
lost through the six-link's drive, and the single four-bar's blow energy."""

import numpy as np

import sweep
from sweep import runner, spec


def test_crank_rocker_designs_become_six_links_whose_drive_pays_for_their_blows(tmp_path):
    """Type b crank_rocker designs -> six_link_forces over beta, the links massless but the
    source's rocker (J5 = rocker_inertia about E): the balancing moment's work over the 4 pi
    cycle is the two blows' loss, J5/2 (u31_j omega1 u_before)^2 (1 - Rk^2) summed, with
    u_before and Rk from the source's synthesis and u31_j from six_link, to 1e-7."""
    inertia = 0.3
    source = tmp_path / "cr.nc"
    sweep.run({"mechanism": "crank_rocker", "grid": {"R": [0.1, 0.3],
                                                      "largest_link": [12.0, 20.0],
                                                      "type": ["b"]},
               "fixed": {"rocker_inertia": inertia}}, source).close()
    massless = {f"{k}{i}": 0.0 for k in ("m", "J") for i in range(1, 5)}
    chained = spec.validate({"mechanism": "six_link_forces", "fixed": massless,
                             "grid": {"from": {"atlas": str(source)},
                                      "beta": [-1.0, 0.0, 0.7]}})
    assert len(chained.notes) == 1 and "crank_length" in chained.notes[0]
    forces = sweep.decode(runner.run_in_memory(chained))
    assert (forces.status.values == "ok").all()
    cr = sweep.decode(sweep.open_atlas(source)).stack(p=["R", "largest_link", "type"])
    cr = cr.isel(p=forces.source_index.values)
    np.testing.assert_array_equal(forces.mu4.values, cr.lambda2.values)
    np.testing.assert_array_equal(forces.mu5.values, cr.lambda3.values)
    six = sweep.decode(sweep.run({
        "mechanism": "six_link", "grid": {"beta": forces.beta.values.tolist(),
                                          "mu4": sorted(set(cr.lambda2.values.tolist())),
                                          "mu5": sorted(set(cr.lambda3.values.tolist()))},
        "outputs": ["transfer_stage1_impact_1", "transfer_stage1_impact_2"]}))
    checked = 0
    for d in range(forces.sizes["design"]):
        blows = six.sel(mu4=float(cr.lambda2.values[d]), mu5=float(cr.lambda3.values[d]))
        before = float(cr.transfer_before.values[d])
        keep = 1 - float(cr.restitution_kinematic.values[d]) ** 2
        for k in range(forces.sizes["beta"]):
            loss = sum(0.5 * inertia * (float(blows[f"transfer_stage1_impact_{j}"][k]) * 30.0
                                        * before) ** 2 for j in (1, 2)) * keep
            np.testing.assert_allclose(float(forces.cycle_work.isel(design=d, beta=k)),
                                       loss, rtol=1e-7)
            checked += 1
    assert checked >= 9


def test_six_links_become_the_single_four_bar_of_their_mean_blow(tmp_path):
    """six_link -> crank_rocker: the second stage alone, a general four-bar, at the crank
    speed of the same mean energy per blow: its blow energy is the mean of the six-link's
    two, its Rk the six-link's, to 1e-12."""
    source = tmp_path / "six.nc"
    sweep.run({"mechanism": "six_link", "grid": {"beta": [0.0, 0.7, -2.0],
                                                 "mu5": [2.5, 4.0]},
               "fixed": {"rocker_inertia": 0.3},
               "outputs": ["blow_energy_1", "blow_energy_2", "restitution_kinematic",
                           "transfer_stage1_impact_1", "transfer_stage1_impact_2"]},
              source).close()
    single = sweep.decode(sweep.run({
        "mechanism": "crank_rocker", "outputs": ["blow_energy", "restitution_kinematic"],
        "grid": {"from": {"atlas": str(source)}}}))
    six = sweep.decode(sweep.open_atlas(source)).stack(p=["beta", "mu5"])
    six = six.isel(p=single.source_index.values)
    assert (single.status.values == "ok").all()
    np.testing.assert_allclose(single.blow_energy.values,
                               (six.blow_energy_1.values + six.blow_energy_2.values) / 2,
                               rtol=1e-12)
    np.testing.assert_allclose(single.restitution_kinematic.values,
                               six.restitution_kinematic.values, rtol=1e-12)


def test_a_source_of_one_type_held_fixed_meets_the_chains_condition_by_it(tmp_path):
    """A chain's condition (type == "b") reads a parameter the source held fixed: a type b
    atlas chains, a type a atlas is refused in one line before any compute."""
    for kind, chains in (("b", True), ("a", False)):
        source = tmp_path / f"cr_{kind}.nc"
        sweep.run({"mechanism": "crank_rocker",
                   "grid": {"R": [0.1, 0.3], "largest_link": [12.0, 16.0]},
                   "fixed": {"type": kind}}, source).close()
        chained = {"mechanism": "six_link", "grid": {"from": {"atlas": str(source)}}}
        if chains:
            assert spec.validate(chained).shape[0] >= 2
        else:
            try:
                spec.validate(chained)
            except sweep.UserError as err:
                assert "type" in str(err) and "\n" not in str(err)
            else:
                raise AssertionError("a type a source chained to six_link")
