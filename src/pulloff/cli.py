"""Command line: ``pulloff run | show | plot``."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from . import __version__


def _cmd_run(args) -> int:
    from . import solvers
    from .io import console as report, h5 as h5io
    from .io.scene_file import load_scene, scene_to_yaml

    scene = load_scene(args.config, overrides=args.set or ())
    out = Path(args.output) if args.output else None
    if out is None and scene.output.path:
        out = Path(scene.output.path)
    if out is None:
        out = Path("runs") / f"{scene.name or Path(args.config).stem}.h5"
    _check_writable(out, "-o/output.path")
    with h5io.atomic_file(out) as f:
        # A fixed-step run streams its history into the file while it runs.
        stream = h5io.HistoryStream(f) if scene.numerics.steps is not None else None
        result = solvers.simulate(scene, progress=_progress(args), stream=stream)
        record = h5io.result_to_record(result, scene_to_yaml(scene))
        h5io.fill(f, record, history_streamed=result.history_streamed)
        if stream is not None:
            record["history_rows_in_file"] = stream.rows
    print(report.format_table(record, title=f"{scene.name or args.config}"))
    if args.no_plot:
        print(f"  wrote {out}")
    else:
        from .io import plots

        png = out.with_suffix(".png")
        plots.plot_history(record, png, title=scene.name or Path(args.config).stem)
        print(f"  wrote {out} and {png}")
    if not result.complete:
        print("  interrupted: the file holds the history computed so far and is marked "
              "complete = False", file=sys.stderr)
        return 130
    return 0


def _cmd_sweep(args) -> int:
    from .io import console as report
    from .io.scene_file import load_scene
    from .studies import sweeps as sweep_mod

    scene = load_scene(args.config, overrides=args.set or ())
    axes = [sweep_mod.parse_axis(text) for text in args.vary]
    _check_writable(Path(args.output), "-o")
    start = time.perf_counter()
    result = sweep_mod.sweep(scene, axes, out=args.output, workers=args.workers,
                             scheduler=args.scheduler, histories=args.histories,
                             progress=_show_progress(args))
    print(report.format_sweep(result))
    print(f"  {time.perf_counter() - start:.1f} s; wrote {args.output}")
    return 0


def _show_progress(args) -> bool:
    """A progress bar only on a terminal, and not with --quiet."""
    return not args.quiet and sys.stderr.isatty()


def _progress(args):
    """The progress hook of a run (:class:`pulloff.solvers.observers.Observers`)."""
    from .io.console import progress_bar

    if not _show_progress(args):
        return None
    return lambda desc, total=None: progress_bar(True, desc, total)


def _check_writable(path: Path, key: str) -> None:
    """Fail before any work if the result could not be written."""
    if path.is_dir():
        raise ValueError(f"{key} = {path}: is a directory, not a file name")
    parent = path.parent if str(path.parent) else Path(".")
    if parent.exists() and not parent.is_dir():
        raise ValueError(f"{key} = {path}: {parent} is not a directory")


def _cmd_validate(args) -> int:
    from .studies import validate

    report_path = validate.validate(args.output, rtol=args.rtol, small=args.small,
                                    workers=args.workers,
                                    progress=_show_progress(args))
    print(f"wrote {report_path} and its figures")
    return 0


#: History rows read to show or draw a run; a streamed history may hold millions.
_SHOWN_ROWS = 100_000


def _cmd_show(args) -> int:
    from .io import console as report, h5 as h5io

    if _is_sweep(args.file):
        from .studies.sweeps import load_sweep

        print(report.format_sweep(load_sweep(args.file)))
        return 0
    record = h5io.load(args.file, history_rows=_SHOWN_ROWS)
    print(report.format_table(record, title=str(args.file)))
    if not record["complete"]:
        print("  (file marked incomplete)")
    return 0


def _is_sweep(path) -> bool:
    from .io import h5 as h5io

    with h5io.open_for_reading(path) as f:
        return f.attrs.get("kind") == "sweep"


def _cmd_plot(args) -> int:
    from .io import h5 as h5io, plots

    png = Path(args.output) if args.output else Path(args.file).with_suffix(".png")
    if _is_sweep(args.file):
        from .studies.sweeps import load_sweep

        plots.plot_sweep(load_sweep(args.file), png, title=str(args.file))
    else:
        plots.plot_history(h5io.load(args.file, history_rows=_SHOWN_ROWS), png,
                           title=str(args.file))
    print(f"wrote {png}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pulloff",
        description="Pull-off of a flat punch from a Kelvin-Voigt half-space (MDR + Dugdale).")
    parser.add_argument("--version", action="version", version=f"pulloff {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="simulate a scene, write HDF5 + PNG, print the table")
    run.add_argument("config", help="scene YAML file")
    run.add_argument("-o", "--output", help="HDF5 file to write (default: output.path or "
                                            "runs/NAME.h5)")
    run.add_argument("--set", action="append", metavar="SECTION.KEY=VALUE",
                     help="override a scene value; repeatable")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    run.add_argument("--no-plot", action="store_true",
                     help="write no PNG (and load no plotting library): batch and long runs")
    run.set_defaults(func=_cmd_run)

    sw = sub.add_parser("sweep", help="run a scene over a grid of parameters, one row each")
    sw.add_argument("config", help="base scene YAML file")
    sw.add_argument("--vary", action="append", required=True, metavar="SECTION.KEY=SPEC",
                    help="an axis: lin:START:STOP:COUNT, log:START:STOP:COUNT or v1,v2,...; "
                         "repeat for a full product grid")
    sw.add_argument("-o", "--output", required=True, help="sweep HDF5 file (resumed if it "
                                                          "holds the same sweep)")
    sw.add_argument("--set", action="append", metavar="SECTION.KEY=VALUE",
                    help="override a base scene value; repeatable")
    sw.add_argument("--workers", type=int, default=None,
                    help="worker processes (default: all cores)")
    sw.add_argument("--scheduler", metavar="ADDRESS",
                    help="run on a Dask distributed cluster (pip install -e \".[dask]\")")
    sw.add_argument("--histories", action="store_true", help="also store each history")
    sw.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    sw.set_defaults(func=_cmd_sweep)

    val = sub.add_parser("validate", help="redraw the seed's figures against the exact model "
                                          "and write a validation report")
    val.add_argument("-o", "--output", default="validation", help="folder (default: validation)")
    val.add_argument("--rtol", type=float, default=1e-5,
                     help="accuracy of each simulation (default 1e-5)")
    val.add_argument("--small", action="store_true", help="coarse grids (a quick check)")
    val.add_argument("--workers", type=int, default=None, help="worker processes")
    val.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    val.set_defaults(func=_cmd_validate)

    show = sub.add_parser("show", help="print the table of a run or sweep file")
    show.add_argument("file")
    show.set_defaults(func=_cmd_show)

    plot = sub.add_parser("plot", help="redraw the figure of a run file, or draw a sweep's "
                                        "force against its first numeric axis")
    plot.add_argument("file")
    plot.add_argument("-o", "--output", help="PNG to write (default: next to the file)")
    plot.set_defaults(func=_cmd_plot)
    return parser


def main(argv=None) -> int:
    from .model.scene import SceneError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except BrokenPipeError:
        # `pulloff show FILE | head`: the reader left; that is not an error of ours.
        sys.stderr.close()
        return 0
    except (SceneError, ValueError, OSError) as exc:
        print(f"pulloff {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"pulloff {args.command}: interrupted; no partial file written (a sweep keeps "
              f"its finished rows: run the same command to resume)", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug: say so in one line, with what to report
        print(f"pulloff {args.command}: internal error: {type(exc).__name__}: {exc} "
              f"(please report it with the scene file)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
