"""Reference atlases for a redesign: write the atlases of every built-in example and of a
set of integrator specs (every pendulum model x tool, DOPRI5 and RK4, the stability and
attractor outputs) and of machine specs (every on-request output and profile, each law,
motor and start), then compare two such folders variable by variable.

Run:  .venv/bin/python benchmarks/reference_atlases.py write DIR
      .venv/bin/python benchmarks/reference_atlases.py compare OLD NEW

``compare`` prints, per file and variable, "identical" or how many values differ and by how
much (largest absolute and relative difference, and where NaN patterns or flags differ);
attributes that record the run (history, code version, versions) are not compared.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SWEEP = Path(sys.executable).with_name("sweep")

#: integrator specs beside the examples: each model x tool, by each fixed method, with the
#: on-request outputs (multipliers, margins, attractors)
_PENDULUM = """mechanism = "rotary_pendulum"
outputs = {outputs}
[grid]
{grid}
[fixed]
model = "{model}"
tool = "{tool}"
k = {k}
kappa = 1.2
omega1 = 40.0
l2 = 0.04
rotor_inertia_ratio = 60.0
motor_slope = 20.0
[method]
{method}
"""
_STABILITY = ('["regime", "amplitude", "frequency_ratio", "impact_speed", "impact_interval", '
              '"impacts_to_converge", "acceleration_peak", "rotor_speed_ratio", "n_steps", '
              '"n_rejected", "n_events", "multiplier_modulus", "multiplier_angle", '
              '"impact_speed_min_ratio", "attractor_count", "basin_fraction"]')
_DEFAULT = ('["regime", "amplitude", "frequency_ratio", "impact_speed", "impact_interval", '
            '"impacts_to_converge", "acceleration_peak", "rotor_speed_ratio", "n_steps", '
            '"n_rejected", "n_events"]')


def extra_specs() -> dict[str, str]:
    specs = {}
    for model in ("paper", "rigid", "rotor"):
        for tool in ("rotor_stop", "lab_window"):
            if tool == "rotor_stop":
                grid = ('k = {start = 1.0, stop = 2.5, num = 7}\n'
                        'R = {start = 0.0, stop = 0.2, num = 5}')
                k = "" if model == "paper" else "1.5"
            else:
                grid = ('tool_window = {start = 0.1, stop = 0.5, num = 9}\n'
                        'R = {start = 0.0, stop = 0.01, num = 4}')
                k = "2.5" if model == "paper" else "1.0"
            fixed_k = k or "2.0"
            for method, text, outputs in (
                    ("dopri5", 'integrator = "dopri5"\nrtol = 1e-9\natol = 1e-11\nstarts = 3\n'
                     'max_impacts = 300', _STABILITY),
                    ("rk4", 'integrator = "rk4"\ndt = 0.005\nmax_impacts = 300', _DEFAULT)):
                body = _PENDULUM.format(outputs=outputs, grid=grid, model=model, tool=tool,
                                        k=fixed_k, method=text)
                if tool == "rotor_stop":
                    body = body.replace(f"k = {fixed_k}\n", "", 1)
                if model == "paper":
                    body = body.replace("kappa = 1.2\n", "")
                if model != "rotor":
                    body = body.replace("rotor_inertia_ratio = 60.0\nmotor_slope = 20.0\n", "")
                if method == "dopri5" and model != "rotor" and tool == "rotor_stop":
                    body = body.replace('"multiplier_modulus", "multiplier_angle", ', "")
                specs[f"{model}_{tool}_{method}"] = body
    specs.update(_MACHINES)
    return specs


#: the impact machine with every on-request output and its profiles, by each law, motor
#: law and start, a sized flywheel and a load on the rocker
_MACHINE_OUTPUTS = ('["mean_crank_speed", "speed_fluctuation", "crank_speed_before_blow", '
                    '"crank_impulse", "motor_power_mean", "motor_torque_rms", "blow_energy", '
                    '"blow_loss", "capture_loss", "blow_efficiency", "energy_balance_residual",'
                    ' "revolutions", "n_steps", "dynamic_force_peak_A", "dynamic_force_peak_B",'
                    ' "dynamic_force_peak_C", "dynamic_force_peak_D", "crank_speed", '
                    '"crank_acceleration", "motor_torque", "shaft_torque"{extra}]')
_MACHINES = {
    "machine_generalized": f"""mechanism = "impact_machine"
outputs = {_MACHINE_OUTPUTS.format(extra=', "flywheel_for_delta", "flywheel_for_delta_classical"')}
[grid]
R = {{start = 0.1, stop = 0.5, num = 5}}
type = ["a", "b", "c"]
[fixed]
largest_link = 2.5
design_restitution = 0.3
flywheel_inertia = 2.0
load_force_x = 200.0
load_arm = 0.1
[method]
profile_points = 24
peak_samples = 61
""",
    "machine_kinematic_rest": f"""mechanism = "impact_machine"
outputs = {_MACHINE_OUTPUTS.format(extra="")}
[grid]
R = {{start = 0.1, stop = 0.5, num = 5}}
motor_law = ["linear", "constant"]
[fixed]
impact_law = "kinematic"
largest_link = 2.5
[method]
start = "rest"
profile_points = 16
peak_samples = 41
""",
    "machine_sized": """mechanism = "impact_machine"
[grid]
R = {start = 0.1, stop = 0.5, num = 4}
[fixed]
flywheel_inertia = "for_delta_target"
[method]
delta_target = 0.05
""",
}


def write(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    listing = subprocess.run([str(SWEEP), "examples"], capture_output=True, text=True,
                             check=True).stdout
    for stem in (line.split()[0] for line in listing.splitlines() if line.strip()):
        spec = folder / f"{stem}.toml"
        subprocess.run([str(SWEEP), "examples", stem, "-o", str(spec)], check=True,
                       capture_output=True)
        _run(spec, folder / f"{stem}.nc")
    for stem, text in extra_specs().items():
        spec = folder / f"{stem}.toml"
        spec.write_text(text)
        _run(spec, folder / f"{stem}.nc")


def _run(spec: Path, atlas: Path) -> None:
    out = subprocess.run([str(SWEEP), "run", str(spec), "-o", str(atlas), "--force", "-q"],
                         capture_output=True, text=True)
    print(f"{atlas.name}: {'written' if out.returncode == 0 else out.stderr.strip()}",
          flush=True)


def compare(old: Path, new: Path) -> int:
    import xarray as xr

    differing = 0
    for a in sorted(old.glob("*.nc")):
        b = new / a.name
        if not b.exists():
            print(f"{a.name}: missing in {new}")
            differing += 1
            continue
        with xr.open_dataset(a, mask_and_scale=False) as da, \
                xr.open_dataset(b, mask_and_scale=False) as db:
            lines = []
            for name in sorted(set(da.variables) | set(db.variables)):
                if name not in da.variables or name not in db.variables:
                    lines.append(f"  {name}: only in one file")
                    continue
                x, y = np.asarray(da[name].values), np.asarray(db[name].values)
                if x.shape != y.shape:
                    lines.append(f"  {name}: shapes {x.shape} and {y.shape}")
                    continue
                if x.dtype.kind not in "fiu":
                    if not np.array_equal(x, y):
                        lines.append(f"  {name}: differs")
                    continue
                xf, yf = x.astype(float), y.astype(float)
                same = (xf == yf) | (np.isnan(xf) & np.isnan(yf))
                if same.all():
                    continue
                nan_changed = int((np.isnan(xf) != np.isnan(yf)).sum())
                both = ~np.isnan(xf) & ~np.isnan(yf) & ~same
                detail = f"{int((~same).sum())} of {same.size} values differ"
                if both.any():
                    abs_diff = np.abs(xf[both] - yf[both])
                    rel = abs_diff / np.maximum(np.abs(xf[both]), 1e-300)
                    detail += f", largest {abs_diff.max():.3g} (relative {rel.max():.3g})"
                if nan_changed:
                    detail += f", {nan_changed} NaN patterns changed"
                lines.append(f"  {name}: {detail}")
            print(f"{a.name}: {'identical' if not lines else 'differs'}")
            for line in lines:
                print(line)
            differing += bool(lines)
    return differing


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "write":
        write(Path(sys.argv[2]))
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(1 if compare(Path(sys.argv[2]), Path(sys.argv[3])) else 0)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
