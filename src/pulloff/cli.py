"""Command line: ``pulloff run | show | plot``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import __version__


def _cmd_run(args) -> int:
    from . import h5io, plots, report, scene as scene_mod, solver

    scene = scene_mod.load_scene(args.config, overrides=args.set or ())
    out = Path(args.output) if args.output else None
    if out is None and scene.output.path:
        out = Path(scene.output.path)
    if out is None:
        out = Path("runs") / f"{scene.name or Path(args.config).stem}.h5"
    result = solver.simulate(scene, progress=not args.quiet and sys.stderr.isatty())
    record = h5io.result_to_record(result, scene_mod.scene_to_yaml(scene))
    h5io.write(out, record)
    png = out.with_suffix(".png")
    plots.plot_history(record, png, title=scene.name or Path(args.config).stem)
    print(report.format_table(record, title=f"{scene.name or args.config}"))
    print(f"  wrote {out} and {png}")
    return 0


def _cmd_show(args) -> int:
    from . import h5io, report

    record = h5io.load(args.file)
    print(report.format_table(record, title=str(args.file)))
    if not record["complete"]:
        print("  (file marked incomplete)")
    return 0


def _cmd_plot(args) -> int:
    from . import h5io, plots

    record = h5io.load(args.file)
    png = Path(args.output) if args.output else Path(args.file).with_suffix(".png")
    plots.plot_history(record, png, title=str(args.file))
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
    run.set_defaults(func=_cmd_run)

    show = sub.add_parser("show", help="print the table of a result file")
    show.add_argument("file")
    show.set_defaults(func=_cmd_show)

    plot = sub.add_parser("plot", help="redraw the figure of a result file")
    plot.add_argument("file")
    plot.add_argument("-o", "--output", help="PNG to write (default: next to the file)")
    plot.set_defaults(func=_cmd_plot)
    return parser


def main(argv=None) -> int:
    from .scene import SceneError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (SceneError, ValueError, FileNotFoundError) as exc:
        print(f"pulloff {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"pulloff {args.command}: interrupted; no file written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
