"""Command line: ``pulloff run | sweep | validate | show | plot``.

Every mistake a user can make (a bad scene, axis, option or output path) ends in exit status
2 with one line naming the key, the value and the reason, before any work and without leaving
a file behind. Ctrl-C, SIGTERM and SIGHUP stop a run or a sweep the same way: what was
computed is kept in a valid file marked incomplete (exit 128 + the signal's number).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from pathlib import Path

from . import __version__

#: The signal that stopped the command (SIGINT for Ctrl-C), for the exit status.
_STOPPED_BY = {"signal": signal.SIGINT}


def _cmd_run(args) -> int:
    from . import solvers
    from .io import console as report, h5 as h5io
    from .io.scene_file import load_scene, scene_to_yaml

    if args.output is not None:
        out, key = args.output, "-o"
    scene = load_scene(args.config, overrides=args.set or ())
    if args.output is None:
        if scene.output.path:
            out, key = scene.output.path, "output.path"
        else:
            out, key = str(Path("runs") / f"{scene.name or Path(args.config).stem}.h5"), \
                "the default output (runs/NAME.h5)"
    out = h5io.check_target(out, key)
    png = None if args.no_plot else out.with_suffix(".png")
    if png is not None:
        if png == out:
            raise h5io.OutputError(f"{key} = {out}: the figure would be written over the "
                                   f"result; give the result file a .h5 name")
        h5io.check_target(png, f"{key} (its figure)")
    title = scene.name or Path(args.config).stem
    with h5io.output_lock(out, key):
        if png is not None:
            for stale in h5io.stale_temp_files(png):  # of a killed earlier run
                stale.unlink(missing_ok=True)
        with h5io.atomic_file(out, key) as f:
            # A fixed-step run streams its history into the file while it runs.
            stream = h5io.HistoryStream(f) if scene.numerics.steps is not None else None
            _compile_notice(args, scene)
            result = solvers.simulate(scene, progress=_progress(args), stream=stream)
            record = h5io.result_to_record(result, scene_to_yaml(scene))
            h5io.fill(f, record, history_streamed=result.history_streamed)
            if stream is not None:
                record["history_rows_in_file"] = stream.rows
        print(report.format_table(record, title=title))
        if png is None:
            print(f"  wrote {out}")
        else:
            try:
                from .io import plots

                plots.plot_history(record, png, title=title)
            except KeyboardInterrupt:
                print(f"  wrote {out}")
                print(f"pulloff run: {_stop_name()} while drawing {png}: {out} is written "
                      f"(complete = {result.complete}); no figure", file=sys.stderr)
                return _stop_status()
            print(f"  wrote {out} and {png}")
    if not result.complete:
        print(f"pulloff run: {_stop_name()}: {out} holds the history computed so far and is "
              f"marked complete = False", file=sys.stderr)
        return _stop_status()
    return 0


def _cmd_sweep(args) -> int:
    from .io import console as report, h5 as h5io
    from .io.scene_file import load_scene
    from .studies import sweeps as sweep_mod

    out = h5io.check_target(args.output, "-o")
    max_points = args.max_points
    axes = [sweep_mod.parse_axis(text, max_points) for text in args.vary]
    sweep_mod.check_size(sweep_mod.grid_size(axes), max_points)
    scene = load_scene(args.config, overrides=args.set or ())
    start = time.perf_counter()
    try:
        result = sweep_mod.sweep(scene, axes, out=out, workers=args.workers,
                                 scheduler=args.scheduler, histories=args.histories,
                                 progress=_show_progress(args), max_points=max_points)
    except KeyboardInterrupt:
        print(f"pulloff sweep: {_stop_name()}: {out} keeps the finished rows and is marked "
              f"incomplete; run the same command to resume", file=sys.stderr)
        return _stop_status()
    print(report.format_sweep(result))
    print(f"  {time.perf_counter() - start:.1f} s; wrote {out}")
    return 0


def _compile_notice(args, scene) -> None:
    """Say once, before a first run's long silence, that the kernels the scene's solver needs
    are being compiled."""
    from . import solvers
    from .kernels import cache_is_warm

    kernel = solvers.route(scene).kernel
    if not getattr(args, "quiet", False) and kernel is not None and not cache_is_warm(kernel):
        print("pulloff: compiling the numba kernels for this machine (first run only: "
              "2-5 s for an onset, 5-15 s with steps, 20-50 s for a moving contact edge)",
              file=sys.stderr, flush=True)


def _show_progress(args) -> bool:
    """A progress bar only on a terminal, and not with --quiet."""
    return not args.quiet and sys.stderr.isatty()


def _progress(args):
    """The progress hook of a run (:class:`pulloff.solvers.observers.Observers`)."""
    from .io.console import progress_bar

    if not _show_progress(args):
        return None
    return lambda desc, total=None: progress_bar(True, desc, total)


def _cmd_validate(args) -> int:
    from .io import h5 as h5io
    from .studies import validate

    if args.output is None:
        # --small never replaces the committed report unless -o says so.
        out = validate.SMALL_OUTPUT if args.small else validate.FULL_OUTPUT
    else:
        if not args.output.strip():
            raise h5io.OutputError("-o: empty path; give a folder")
        out = Path(args.output)
    report_path = validate.validate(out, rtol=args.rtol, small=args.small,
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

        result = load_sweep(args.file)
        if args.csv:
            report.write_sweep_csv(result, sys.stdout)
            return 0
        print(report.format_sweep(result, title=_title(result.name, args.file)))
        return 0
    if args.csv:
        record = h5io.load(args.file)
        report.write_history_csv(record, sys.stdout)
        return 0
    record = h5io.load(args.file, history_rows=_SHOWN_ROWS)
    print(report.format_table(record, title=_title(report.scene_name(record), args.file)))
    if not record["complete"]:
        print("  (file marked incomplete)")
    return 0


def _title(name, path) -> str:
    """A file's scene name (the file name where it has none)."""
    return str(name) if name else Path(path).stem


def _is_sweep(path) -> bool:
    from .io import h5 as h5io

    with h5io.open_for_reading(path) as f:
        return f.attrs.get("kind") == "sweep"


def _cmd_plot(args) -> int:
    from .io import console as report, h5 as h5io, plots

    if args.output is not None:
        png = h5io.check_target(args.output, "-o")
    else:
        png = h5io.check_target(Path(args.file).with_suffix(".png"),
                                "the default figure (FILE.png)")
    if png.resolve() == Path(args.file).resolve():
        raise h5io.OutputError(f"-o = {png}: is the file being drawn; choose a .png name")
    if _is_sweep(args.file):
        from .studies.sweeps import load_sweep

        result = load_sweep(args.file)
        plots.plot_sweep(result, png, title=_title(result.name, args.file))
    else:
        record = h5io.load(args.file, history_rows=_SHOWN_ROWS)
        plots.plot_history(record, png, title=_title(report.scene_name(record), args.file))
    print(f"wrote {png}")
    return 0


def _whole_number(minimum: int):
    def parse(text: str) -> int:
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{value} is below {minimum}")
        return value
    parse.__name__ = f"whole number >= {minimum}"
    return parse


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number > 0")
    return value


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (usage stays on ``--help``), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from .studies.sweeps import MAX_POINTS

    parser = _Parser(
        prog="pulloff",
        description="Adhesive contact and pull-off of rigid indenters (flat punches, spheres, "
                    "cones, power-law tips) from elastic and visco-elastic half-spaces "
                    "(Kelvin-Voigt, standard linear solid, Prony series), at constant speed or "
                    "along loading paths: the method of dimensionality reduction with a "
                    "Dugdale cohesive zone.")
    parser.add_argument("--version", action="version", version=f"pulloff {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    run = sub.add_parser("run", help="simulate a scene, write HDF5 + PNG, print the table")
    run.add_argument("config", help="scene YAML file")
    run.add_argument("-o", "--output", help="HDF5 file to write (default: output.path or "
                                            "runs/NAME.h5)")
    run.add_argument("--set", action="append", metavar="SECTION.KEY=VALUE",
                     help="override a scene value (a list item by its index: "
                          "material.terms.0.G=2e6); repeatable")
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
    sw.add_argument("--workers", type=_whole_number(1), default=None,
                    help="worker processes, >= 1 (default: all cores)")
    sw.add_argument("--max-points", type=_whole_number(1), default=MAX_POINTS,
                    help=f"largest grid to run (default {MAX_POINTS}); a larger one is "
                         f"refused before any work")
    sw.add_argument("--scheduler", metavar="ADDRESS",
                    help="run on a Dask distributed cluster (pip install -e \".[dask]\")")
    sw.add_argument("--histories", action="store_true", help="also store each history")
    sw.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    sw.set_defaults(func=_cmd_sweep)

    val = sub.add_parser("validate", help="redraw the seed's figures against the exact model "
                                          "and write a validation report")
    val.add_argument("-o", "--output", default=None,
                     help="folder (default: validation; with --small: runs/validation_small, "
                          "so the committed report is never replaced by a coarse one)")
    val.add_argument("--rtol", type=_positive_float, default=1e-5,
                     help="accuracy of each simulation (default 1e-5)")
    val.add_argument("--small", action="store_true", help="coarse grids (a quick check)")
    val.add_argument("--workers", type=_whole_number(1), default=None,
                     help="worker processes, >= 1")
    val.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    val.set_defaults(func=_cmd_validate)

    show = sub.add_parser("show", help="print the table of a run or sweep file")
    show.add_argument("file")
    show.add_argument("--csv", action="store_true",
                      help="print CSV instead: a sweep's table, or a run's history")
    show.set_defaults(func=_cmd_show)

    plot = sub.add_parser("plot", help="redraw the figure of a run file, or draw a sweep's "
                                        "force against its first numeric axis")
    plot.add_argument("file")
    plot.add_argument("-o", "--output", help="PNG to write (default: next to the file)")
    plot.set_defaults(func=_cmd_plot)
    return parser


def _stop_status() -> int:
    return 128 + int(_STOPPED_BY["signal"])


def _stop_name() -> str:
    sig = _STOPPED_BY["signal"]
    return "interrupted (Ctrl-C)" if sig == signal.SIGINT else \
        f"stopped by {signal.Signals(sig).name}"


def _stop_like_ctrl_c(signum, frame):
    """SIGTERM (what schedulers send) and SIGHUP (a closed terminal) stop a command like
    Ctrl-C: the solver or the sweep ends where it is and the file is written, marked
    incomplete. Further ones are ignored while that is done (a SIGKILL still ends it)."""
    _STOPPED_BY["signal"] = signum
    _STOPPED_BY["arrived"] = True
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    raise KeyboardInterrupt


def _quiet_stop_in_callbacks(hook):
    """A stop raised inside a C callback (numba's compiler) cannot propagate and Python would
    print it as ignored: keep the console to the one line the stop reports."""

    def quiet(info):
        if not (_STOPPED_BY.get("arrived") and isinstance(info.exc_value, KeyboardInterrupt)):
            hook(info)
            return
        # Swallowed there, the stop would be lost: deliver it again shortly, in Python code.
        signum = _STOPPED_BY["signal"]
        if signum != signal.SIGINT:
            signal.signal(signum, _stop_like_ctrl_c)
        threading.Timer(0.05, os.kill, (os.getpid(), signum)).start()

    return quiet


def _install_signal_handlers() -> None:
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            try:
                signal.signal(getattr(signal, name), _stop_like_ctrl_c)
            except ValueError:  # not the main thread (main() called from a thread)
                return


def main(argv=None) -> int:
    from .model.scene import SceneError

    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # a usage error (status 2, one line printed), --help, --version
        return exc.code if isinstance(exc.code, int) else 2
    _STOPPED_BY["signal"] = signal.SIGINT
    _STOPPED_BY["arrived"] = False
    previous = {name: signal.getsignal(getattr(signal, name)) for name in ("SIGTERM", "SIGHUP")
                if hasattr(signal, name)}
    _install_signal_handlers()
    unraisable = sys.unraisablehook
    sys.unraisablehook = _quiet_stop_in_callbacks(unraisable)
    try:
        return args.func(args)
    except BrokenPipeError:
        # `pulloff show FILE | head`: the reader left; that is not an error of ours.
        sys.stderr.close()
        return 0
    except (SceneError, ValueError, OSError) as exc:
        print(f"pulloff {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"pulloff {args.command}: {_stop_name()}; no partial file written (a sweep "
              f"keeps its finished rows: run the same command to resume)", file=sys.stderr)
        return _stop_status()
    except Exception as exc:  # a bug: say so in one line, with what to report
        if _STOPPED_BY["arrived"]:
            # The stop landed inside a callback (numba compiling): what failed after it is
            # the stop's doing, not a bug.
            print(f"pulloff {args.command}: {_stop_name()}; no partial file written",
                  file=sys.stderr)
            return _stop_status()
        print(f"pulloff {args.command}: internal error: {type(exc).__name__}: "
              f"{_one_line(exc)} (please report it with the scene file)", file=sys.stderr)
        return 1
    finally:
        sys.unraisablehook = unraisable
        for name, handler in previous.items():
            try:
                signal.signal(getattr(signal, name), handler)
            except (ValueError, TypeError):
                pass


def _one_line(exc: BaseException) -> str:
    """An error as one line: several problems of a scene joined by '; '."""
    problems = getattr(exc, "problems", None)
    text = "; ".join(problems) if problems else str(exc)
    return " ".join(text.split("\n"))


if __name__ == "__main__":
    sys.exit(main())
