"""How well the moving-edge solver's gap integral holds next to a receding zone end.

    python benchmarks/zone_end_quadrature.py [--levels 16 32 64 128] [--every 7]

Once the zone end ``b`` recedes (the contact phase after the onset, the zone alone), the
condition ``gap(b) = delta`` is solved with the gap integral over the elements the edge
released earlier, spaced for the zone of their time. Every ``--every``-th such step at
n = 16 (every ``every n / 16``-th at level n: about as many checks per level), this
script recomputes the integral at the committed state from 800 elements replayed evenly in
angle from the rows (exact states: ``contact_replay.replay``) and reports the largest error of
the gap [delta] the step committed, beside what two remedies would leave:

* ``exact end``: the same elements, but the displacement at ``b`` itself exact (the solver
  extrapolates it from the elements next to the end);
* ``even``: as many elements as the step had, evenly in angle (exact states).

Its output is ``benchmarks/results/zone_end_quadrature.txt``. Single-threaded.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import math  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from common import machine_summary  # noqa: E402
from pulloff.io.scene_file import load_scene  # noqa: E402
from pulloff.kernels import contact as K  # noqa: E402
from pulloff.solvers import contact, contact_replay, contact_state  # noqa: E402
from pulloff.solvers.contact_stepper import Stepper  # noqa: E402

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
#: (label, config, overrides)
SCENES = (("sls_finite_punch", "sls_finite_punch", []),
          ("sls_finite_punch v=1e-7", "sls_finite_punch", ["loading.v=1e-7"]),
          ("prony_external", "prony_external", []),
          ("finite_punch_internal", "finite_punch_internal", []),
          ("separation_kv", "separation_kv", []),
          ("seed_flat_punch", "seed_flat_punch", []))
#: Replayed elements of the reference integral (800 and 400 agree to 1e-7 of the gap or better).
REFERENCE_ELEMENTS = 800


class _Checked(Stepper):
    """A stepper that keeps, at every committed step of a receding zone end, the elements
    its evaluation integrated, and compares the gap there with the replayed reference."""

    def __init__(self, setup, n, t_scale, every):
        super().__init__(setup, n, t_scale)
        self.every, self.seen = every, 0
        self.errors = {"solver": [], "exact end": [], "even": []}

    def commit(self, step, ev):
        inside = (ev.flags != 2) & (ev.xi > ev.alpha) & (ev.xi < ev.beta)
        xs, us = ev.xi[inside].copy(), ev.U[inside].copy()
        super().commit(step, ev)
        now = self.now
        receding = (now.phase in (contact_state.CONTACT_PHASE, contact_state.ZONE)
                    and self.before is not None and now.beta < self.before.beta)
        if receding and now.alpha > 0.0:
            self.seen += 1
            if self.seen % self.every == 0:
                self._compare(xs[np.argsort(xs)], us[np.argsort(xs)])

    def _displacements(self, x, beta):
        law = self.setup.law
        Y = contact_replay.replay(self, x)
        if Y is None:
            return None
        q = np.sqrt(np.maximum((beta - x) * (beta + x), 0.0))
        return law.d * q + (Y[:, :law.n_modes] @ law.ctil if law.n_modes else 0.0)

    def _compare(self, xs, us):
        now = self.now
        a, b, H = now.alpha, now.beta, now.H
        theta_a = math.atan2(math.sqrt((b - a) * (b + a)), a)

        def integral(x, u, u_end):
            return K.free_gap_integral(x, u, 0, x.size, a, b, H, u_end, self.first_edge)

        x_ref = np.sort(b * np.cos(theta_a * np.arange(1, REFERENCE_ELEMENTS)
                                   / REFERENCE_ELEMENTS))
        u_ref = self._displacements(np.append(x_ref, b), b)
        if u_ref is None:
            return
        reference = integral(x_ref, u_ref[:-1], u_ref[-1])
        m = xs.size + 1
        x_even = np.sort(b * np.cos(theta_a * np.arange(1, m) / m))
        u_even = self._displacements(x_even, b)
        to_gap = 2.0 / math.pi
        self.errors["solver"].append(to_gap * abs(integral(xs, us, math.nan) - reference))
        self.errors["exact end"].append(to_gap * abs(integral(xs, us, u_ref[-1]) - reference))
        self.errors["even"].append(to_gap * abs(integral(x_even, u_even, u_ref[-1])
                                                - reference))


def measure(config, overrides, n, every):
    """``(steps checked, largest gap error per method)`` of one level."""
    scene = load_scene(CONFIGS / f"{config}.yaml",
                       overrides=["model.until=separation"] + overrides)
    setup = contact.make_setup(scene)
    t_scale = contact._time_scale(scene, setup)
    t_end = setup.t_max if math.isfinite(setup.t_max) else contact.DEFAULT_SPAN * t_scale
    stepper = _Checked(setup, n, t_scale, every)
    stepper.run(t_end)
    return len(stepper.errors["solver"]), {k: max(v, default=math.nan)
                                           for k, v in stepper.errors.items()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[16, 32, 64, 128])
    ap.add_argument("--every", type=int, default=7)
    args = ap.parse_args(argv)
    print(machine_summary())
    print("largest error of gap(b) [delta] at steps of a receding zone end, against "
          f"{REFERENCE_ELEMENTS} replayed elements")
    print(f"{'scene':26} {'n':>4} {'checked':>8} {'solver':>9} {'exact end':>10} {'even':>9}")
    for label, config, overrides in SCENES:
        for n in args.levels:
            checked, worst = measure(config, overrides, n, max(1, args.every * n // 16))
            print(f"{label:26} {n:4d} {checked:8d} {worst['solver']:9.1e} "
                  f"{worst['exact end']:10.1e} {worst['even']:9.1e}", flush=True)


if __name__ == "__main__":
    main()
