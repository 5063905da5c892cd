"""Work against precision past the onset: the moving-edge (contact) solver to separation.

    python benchmarks/work_precision_separation.py [--max-level-seconds 30]

For every shipped flat-punch config that is pulled to separation and has an independent
moving-edge reference (``tests/data/edge_reference.json``, ``pulloff.references.edge``): the
contact solver's single levels at fixed ``n = 8, 16, 32, ...`` (``contact.run_level``; a level
is about ``n`` steps per time scale), until one level takes longer than
``--max-level-seconds``, and the Richardson extrapolation of each three consecutive levels,
which is what ``simulate`` reports (its time is that of the three levels). Error: the largest
relative error of the onset time and force, the separation time and the peak total force
against the reference. Times are warm (one untimed run of the coarsest level first), medians of
3 runs for levels under a second, single thread. Writes
results/work_precision_separation.{csv,txt,png}: error against time, one line per config,
with the fitted order of the levels in ``n`` and the slope of time against error.
"""

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import csv  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from common import loglog_slope, machine_summary  # noqa: E402
from pulloff.io.scene_file import load_scene  # noqa: E402
from pulloff.solvers import levels  # noqa: E402
from pulloff.solvers.contact import CONTROLLED, ORDER, run_level  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results"
REFERENCE = json.loads((ROOT / "tests" / "data" / "edge_reference.json").read_text())
CONFIGS = ("separation_elastic", "separation_kv", "finite_punch_internal", "sls_finite_punch",
           "prony_external")
#: Summary name -> reference name of what the error is taken over.
JUDGED = {"t_detach": "t_onset", "F_total_detach": "F_onset_total",
          "t_separation": "t_separation", "F_peak_total": "F_peak_total"}
LEVELS = (8, 16, 32, 64, 128, 256, 512)


def error(summary: dict, reference: dict) -> float:
    """Largest relative error of the judged outputs (nan where the run has none)."""
    errs = [abs(summary[k] / reference[r] - 1.0) for k, r in JUDGED.items()
            if math.isfinite(summary.get(k, math.nan))]
    return max(errs) if errs else math.nan


def timed_level(scene, n):
    """``(median seconds, summary)`` of one level; 3 runs when it is under a second."""
    times, run = [], None
    for _ in range(3):
        start = time.perf_counter()
        run = run_level(scene, n)
        times.append(time.perf_counter() - start)
        if times[-1] > 1.0:
            break
    return statistics.median(times), run


def measure(config, max_seconds):
    scene = load_scene(ROOT / "configs" / f"{config}.yaml")
    reference = REFERENCE[config]
    run_level(scene, LEVELS[0])  # warm
    rows, outs, secs = [], [], []
    for n in LEVELS:
        seconds, run = timed_level(scene, n)
        summary = run.summary
        outs.append(np.array([summary.get(k, math.nan) for k in CONTROLLED], dtype=float))
        secs.append(seconds)
        rows.append(dict(config=config, kind="level", n=n, steps=len(run.rows),
                         seconds=seconds, error=error(summary, reference), estimate=""))
        line = f"  {config:<22} n={n:<4} {seconds:8.3f} s  error {rows[-1]['error']:.2e}"
        if len(outs) >= 3:
            values, estimate = levels.extrapolate_measured(outs[-3:], ORDER)
            extrapolated = dict(zip(CONTROLLED, values))
            rows.append(dict(config=config, kind="extrapolated", n=n, steps=len(run.rows),
                             seconds=sum(secs[-3:]), error=error(extrapolated, reference),
                             estimate=estimate))
            line += f"  extrapolated {rows[-1]['error']:.2e} (estimate {estimate:.1e})"
        print(line, flush=True)
        if seconds > max_seconds:
            break
    return rows


def fits(rows):
    """Per config: the levels' order in ``n`` (last three levels above 1e-12) and the slope of
    log time against log error of the extrapolated runs."""
    out = {}
    for config in CONFIGS:
        lv = [r for r in rows if r["config"] == config and r["kind"] == "level"
              and r["error"] > 1e-12]
        ex = [r for r in rows if r["config"] == config and r["kind"] == "extrapolated"
              and r["error"] > 1e-12]
        order = -loglog_slope([r["n"] for r in lv[-3:]], [r["error"] for r in lv[-3:]])
        slope = loglog_slope([r["error"] for r in ex], [r["seconds"] for r in ex])
        out[config] = dict(order=order, time_vs_error=slope)
    return out


def plot(rows, fitted):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    for i, config in enumerate(CONFIGS):
        color = f"C{i}"
        for kind, style in (("level", "o--"), ("extrapolated", "s-")):
            pts = [(r["seconds"], r["error"]) for r in rows
                   if r["config"] == config and r["kind"] == kind and r["error"] > 0]
            if not pts:
                continue
            label = (f"{config} (order {fitted[config]['order']:.2f})" if kind == "level"
                     else None)
            ax.loglog(*zip(*pts), style, color=color, label=label, markersize=4,
                      alpha=0.55 if kind == "level" else 1.0)
    ax.set_xlabel("warm wall time [s]")
    ax.set_ylabel("largest relative error (onset, separation, peak) vs reference")
    ax.set_title("Separation: fixed levels (dashed) and their extrapolation (solid)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(RESULTS / "work_precision_separation.png", dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-level-seconds", type=float, default=30.0)
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    print(machine_summary())
    rows = []
    for config in CONFIGS:
        rows += measure(config, args.max_level_seconds)
    fitted = fits(rows)
    with open(RESULTS / "work_precision_separation.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [machine_summary(),
             f"{'config':<22} {'order in n':>10} {'time ~ error^x':>15}"]
    lines += [f"{c:<22} {f['order']:>10.2f} {f['time_vs_error']:>15.2f}"
              for c, f in fitted.items()]
    (RESULTS / "work_precision_separation.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    plot(rows, fitted)


if __name__ == "__main__":
    main()
