"""Warm run time and accuracy of the shipped configs.

    python benchmarks/shipped_configs.py [--repeat 7]

For each flat-punch pull under configs/ (smooth indenters and loading paths are in
moving_edge_and_paths.py): the first call's time (numba compile or cache load included,
reported on its own), the median and spread of repeated warm runs of ``simulate``, the
achieved relative error against the independent quadrature reference (``pulloff.references.onset``)
and the solver's own error estimate. Single-threaded; numba's threading is not used.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from pulloff.references.onset import reference_detachment
from pulloff.io.scene_file import load_scene
from pulloff.solvers import simulate

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    t0 = time.perf_counter()
    simulate(load_scene(CONFIGS / "seed_flat_punch.yaml"))
    print(f"first call (JIT compile or cache load): {time.perf_counter() - t0:.2f} s")
    header = (f"{'config':<22} {'history':<7} {'F_contact [N]':>14} {'vs closed form':>14} "
              f"{'error':>9} {'estimate':>9} {'steps':>6} {'median ms':>10} {'min-max ms':>14}")
    print(header)
    for path in sorted(CONFIGS.glob("*.yaml")):
        scene = load_scene(path)
        if scene.geometry.kind != "flat_punch" or scene.loading.kind != "constant_velocity":
            continue  # smooth indenters and paths: benchmarks/moving_edge_and_paths.py
        times = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            res = simulate(scene)
            times.append(1e3 * (time.perf_counter() - start))
        p = res.problem
        # The quadrature reference solves the seed's model: Kelvin-Voigt (or elastic) on the
        # external zone, up to the onset, which a run to separation also reports.
        seed_model = (scene.geometry.cohesive_zone == "external"
                      and scene.material.kind in ("kelvin_voigt", "elastic")
                      and scene.loading.machine_stiffness is None)
        if scene.model.history == "exact" and not seed_model:
            error_text = f"{'-':>9}"
        elif scene.model.history == "exact":
            ref = reference_detachment(p.G, p.eta, p.sigma_c, p.delta, p.a, p.v, p.h0,
                                       rtol=1e-11)
            error = max(abs(res.t_detach / ref["t_detach"] - 1),
                        abs(res.F_contact_detach / ref["F_contact"] - 1),
                        abs(res.F_total_detach / ref["F_total"] - 1))
            error_text = f"{error:9.1e}"
        else:
            error_text = f"{'(closed)':>9}"
        closed = res.analytic["seed_closed_form_F"]
        diff = (closed - res.F_contact_detach) / res.F_contact_detach
        print(f"{path.stem:<22} {scene.model.history:<7} {res.F_contact_detach:14.6g} "
              f"{diff:+14.2%} {error_text} {res.error_estimate:9.1e} {res.n_steps:6d} "
              f"{statistics.median(times):10.2f} {min(times):6.2f}-{max(times):<7.2f}")


if __name__ == "__main__":
    main()
