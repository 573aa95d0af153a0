"""The paper model on the rotor stop by heyoka's Taylor integrator: the other side of
benchmarks/bench_heyoka.py, run in the benchmark's own environment (heyoka is not a
dependency of impact-sweep, and this file imports nothing of it).

Each design (k, xi, R) starts at rest on the stop (the first impact at once) and flies
flight after flight, psi' <- -R (1 + k + psi') - (1 + k) at each return to psi = 0 (the
rotor stop's Newton law at constant rotor speed), until the arrival speed repeats to
``repeat`` relative: the steady state. As the core does on this affine section map, after
two flights it jumps to the fixed point of the line through them, so that both sides fly
the same flights (from rest, one more, and from the jump). The Taylor integrator is built
once, with k and xi as runtime parameters, and its build is not timed.

Input (a JSON file, argv[1]): {"designs": [[k, xi, R], ...], "tol": ..., "repeat": ...,
"max_impacts": ...}. Output (stdout, JSON): the CPU seconds of the loop over all designs
(time.process_time), and per design the steady arrival speed, the steps and the flights.
"""

import json
import sys
import time

import heyoka as hy


def integrator(tol):
    psi, dpsi = hy.make_vars("psi", "dpsi")
    k, xi = hy.par[0], hy.par[1]
    x = k * k + 1.0 + 2.0 * k * hy.cos(psi)
    acceleration = -k * x / (1.0 + xi * x) * (dpsi * dpsi + xi) * hy.sin(psi)
    arrival = hy.t_event(psi, direction=hy.event_direction.positive)
    return hy.taylor_adaptive([(psi, dpsi), (dpsi, acceleration)], [0.0, 0.0],
                              pars=[1.0, 4.0], tol=tol, t_events=[arrival])


def steady(ta, k, xi, r, repeat, max_impacts):
    """(steady arrival speed psi', steps, flights) of one design; NaN where the sequence
    does not repeat within max_impacts flights or a flight does not return."""
    ta.pars[:] = (k, xi)
    arrivals, steps = [0.0], 0  # at rest on the stop: arriving at speed 0
    for flight in range(1, max_impacts + 1):
        ta.time = 0.0
        ta.state[:] = (0.0, -r * (1.0 + k + arrivals[-1]) - (1.0 + k))
        outcome = ta.propagate_until(1e3)
        steps += outcome[3]
        if ta.time >= 1e3:
            return float("nan"), steps, flight
        arrival = float(ta.state[1])
        if abs(arrival - arrivals[-1]) <= repeat * abs(arrival):
            return arrival, steps, flight
        arrivals.append(arrival)
        if flight == 2:  # the fixed point of the line through (x0, x1) and (x1, x2)
            x0, x1, x2 = arrivals
            slope = (x2 - x1) / (x1 - x0)
            arrivals.append((x1 - slope * x0) / (1.0 - slope))
    return float("nan"), steps, max_impacts


def main():
    job = json.loads(open(sys.argv[1]).read())
    ta = integrator(job["tol"])
    start = time.process_time()
    found = [steady(ta, k, xi, r, job["repeat"], job["max_impacts"])
             for k, xi, r in job["designs"]]
    cpu = time.process_time() - start
    print(json.dumps({"cpu": cpu, "order": ta.order, "arrival": [f[0] for f in found],
                      "steps": [f[1] for f in found], "flights": [f[2] for f in found]}))


if __name__ == "__main__":
    main()
