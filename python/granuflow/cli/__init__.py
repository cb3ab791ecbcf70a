"""Command line: ``granuflow run | steady | draw | report | sweep | contour | calibrate | describe | units | kernels |
materials | docs | bench``.

Exit codes: 0 success, 2 bad input (scene, option, parameter), 3 solver failure. A failure prints one line
on stderr naming what went wrong. Each command's module is imported only when it runs, so that ``granuflow run``
pays for NumPy and the core alone (matplotlib only when it draws, pandas never).
"""
from __future__ import annotations

import importlib
import os
import sys

from .common import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_SOLVER, Parser, one_line

# What `bench --quick` reduces, per subcommand (cli/bench.py runs it).
_QUICK = {"core": "tank chains of 100 and 1000 states (not 10000)",
          "pbm": "q 1, 2, 4; rtol 1e-2, 1e-4, 1e-6; integrators auto, ida, adams, erk",
          "scene": "10 classes only, SciPy once", "sweep": "a 9 x 9 map, one repeat, no Dask",
          "pbm2d": "20x20 and 40x40 bins, dense LU and SciPy at 20x20, the other sections at 20x20",
          "loop": "50 classes only, one repeat",
          "targets": "no calibration or two-zone study, a 5x5 map, the 2-D scene at 20x20, one repeat"}


# The commands whose output folder records what made it (provenance.json: the command line and the input files'
# text), which `granuflow report` shows.
_PROVENANCE = ("run", "steady", "sweep", "contour", "calibrate")


def _cmd(module: str, name: str):
    """The handler ``name`` of ``granuflow.cli.<module>``, imported when the command runs."""
    def run(args):
        return getattr(importlib.import_module(f"{__name__}.{module}"), name)(args)
    return run


def _add_batch_options(p) -> None:
    """Options shared by the commands that run many points (sweep, contour)."""
    p.add_argument("--workers", type=int, help="parallel solves (default: number of cores)")
    p.add_argument("--set", action="append", metavar="UNIT.PARAM=VALUE",
                   help="override a scene parameter for every point (unit allowed)")
    p.add_argument("--t-end", help="end time of every run in seconds (or with a unit, e.g. '60 min')")
    p.add_argument("--executor", default="threads", choices=["threads", "serial"])
    p.add_argument("--no-progress", action="store_true", help="no progress bar (default: only on a terminal)")
    p.add_argument("--quiet", action="store_true", help="no output but warnings and errors (and no progress bar)")


def _version() -> str:
    from .. import __version__, build_info

    return f"granuflow {__version__} ({build_info()['isa']})"


def _load_plugins(libs: list[str]) -> None:
    """GRANUFLOW_PLUGIN_PATH's refusal at import, then the --plugin libraries: bad input like any other."""
    from .. import _core, plugins

    if plugins.env_error:
        raise _core.ConfigError(f"{plugins.ENV_PATH}: {plugins.env_error}")
    for lib in libs:
        plugins.load_plugin(lib)


class _Unbuilt:
    """The parser of a command this run does not name: argparse's parsers of all commands would cost every run ~10
    ms (issue 32); the one named is built as ever, so its options, help and errors are the same."""

    def add_argument(self, *args, **kwargs):
        pass

    def set_defaults(self, **kwargs):
        pass


def _named_command(argv: list[str]) -> str | None:
    """The command of a command line whose words before it are only ``--plugin LIB`` (or ``--plugin=LIB``); None
    for anything else (help, --version, an abbreviated option), for which every command's parser is built."""
    k = 0
    while k < len(argv) and (argv[k] == "--plugin" or argv[k].startswith("--plugin=")):
        k += 2 if argv[k] == "--plugin" else 1
    return argv[k] if k < len(argv) and not argv[k].startswith("-") else None


def _parser(named: str | None):
    """(the command line's parser, its subparsers) with the parser of command ``named`` only, or of all (None)."""
    p = Parser(prog="granuflow", description="spray fluidized-bed flowsheet simulation")
    p.add_argument("--version", action="version", version=_version())
    p.add_argument("--plugin", action="append", default=[], metavar="LIB",
                   help="load units and kernels from a plugin library first (repeatable; docs/install_and_plugins.md)")
    sub = p.add_subparsers(dest="cmd", required=True, parser_class=Parser)

    def add_parser(name: str, **kwargs):
        return sub.add_parser(name, **kwargs) if named in (None, name) else _Unbuilt()

    r = add_parser("run", help="simulate a scene and write summary.json, CSV and plots")
    r.add_argument("scene")
    r.add_argument("--out", required=True, help="output folder (created)")
    r.add_argument("--set", action="append", metavar="UNIT.PARAM=VALUE", help="override a parameter (unit allowed)")
    r.add_argument("--t-end", help="end time in seconds (or with a unit, e.g. '60 min')")
    r.add_argument("--no-plots", action="store_true", help="write summary.json and timeseries.csv only (faster)")
    r.add_argument("--error-estimate", action="store_true",
                   help="re-solve on size grids 2 and 4 times finer and at a 100 times tighter tolerance; the "
                        "estimated numerical error of every summary output goes to summary.json and the plots")
    r.add_argument("--accuracy", metavar="TARGET",
                   help="refine the size grid and tolerance until the estimated error of every summary output is "
                        "below TARGET (e.g. 1%%), or of the named ones (d50_um=1%%,d90_um=3%%); 'off': the scene's "
                        "grid as written")
    r.add_argument("--no-grid-check", action="store_true",
                   help="skip the check of the size grid (one solve on a grid twice as fine)")
    r.add_argument("--checkpoint-at", metavar="TIMES",
                   help="write the run's full state at these times to checkpoint_<t>s.gfckpt in --out (comma-"
                        "separated, e.g. '10 min,30 min'; replaces the scene's checkpoints:)")
    r.add_argument("--restart", metavar="FILE",
                   help="resume from a checkpoint file of the same scene (bit-identical to the run that wrote it)")
    r.add_argument("--quiet", action="store_true", help="no output but warnings and errors")
    r.set_defaults(func=_cmd("run", "cmd_run"))
    st = add_parser("steady", help="solve a scene's steady state directly; write steady.json and steady_psd.csv")
    st.add_argument("scene")
    st.add_argument("--out", required=True, help="output folder (created)")
    st.add_argument("--set", action="append", metavar="UNIT.PARAM=VALUE", help="override a parameter (unit allowed)")
    st.add_argument("--t", help="time at which scheduled inputs are evaluated (s, or with a unit: '70 h'; default 0)")
    st.add_argument("--no-stability", action="store_true", help="skip the eigenvalues of the linearized dynamics")
    st.add_argument("--quiet", action="store_true", help="no output but warnings and errors")
    st.set_defaults(func=_cmd("steady", "cmd_steady"))
    dr = add_parser("draw", help="draw a scene's flowsheet with Graphviz (units, streams, recycles)")
    dr.add_argument("scene")
    dr.add_argument("--out", required=True, help="image file: .svg, .png, .pdf or .dot")
    dr.set_defaults(func=_cmd("info", "cmd_draw"))
    rp = add_parser("report", help="write OUT_DIR/report.html: one offline page with the diagram, results, "
                    "balances, warnings, plots, scene and command of a finished output folder")
    rp.add_argument("out_dir")
    rp.set_defaults(func=_cmd("info", "cmd_report"))
    w = add_parser("sweep", help="run a sweep file; write sweep.csv and sweep.json")
    w.add_argument("sweepfile")
    w.add_argument("--out", required=True, help="output folder (created)")
    _add_batch_options(w)
    w.add_argument("--fail-fast", action="store_true", help="stop at the first failed point (exit 3)")
    w.add_argument("--error-estimate", action="store_true",
                   help="each point also on finer size grids and a tighter tolerance: columns <output>_err")
    w.set_defaults(func=_cmd("sweep", "cmd_sweep"))
    k = add_parser("contour", help="contour map of outputs over two parameters; feasible window; CSV and PNG")
    k.add_argument("scene")
    k.add_argument("--x", required=True, metavar="UNIT.PARAM:UNIT:LO:HI:N",
                   help="e.g. inlet.T:degC:40:80:15 (N: 1 to 401 points), or a unit setting's values "
                        "UNIT.SETTING=V1,V2,... (particles.classes=10,20,40,80; bed.aggregation=kapur,sum)")
    k.add_argument("--y", required=True, metavar="UNIT.PARAM:UNIT:LO:HI:N",
                   help="e.g. nozzle.mdot:g/min:60:120:15 (N: 1 to 401 points), or UNIT.SETTING=V1,V2,...")
    k.add_argument("--output", action="append", help="summary key or state/output name (repeatable; default d50_um)")
    k.add_argument("--constraint", action="append", metavar="OUTPUT>=VALUE", help='e.g. "bed_moisture_wet<0.04"')
    k.add_argument("--out", required=True, help="output folder (created)")
    _add_batch_options(k)
    k.add_argument("--dask", metavar="ADDRESS", help="run on the Dask scheduler at ADDRESS (tcp://host:8786)")
    k.add_argument("--error-estimate", action="store_true",
                   help="each point also on finer size grids and a tighter tolerance: a map of each output's "
                        "estimated numerical error (contour_<output>_err.png) next to the output's")
    k.add_argument("--steady", action="store_true",
                   help="each point's steady state, solved directly (continuous processes), instead of a run")
    k.set_defaults(func=_cmd("contour", "cmd_contour"))
    u = add_parser("units", help="the built-in unit types; with NAME its ports, settings, parameters, outputs")
    u.add_argument("name", nargs="?", help="a unit type (e.g. fluid_bed)")
    u.set_defaults(func=_cmd("info", "cmd_units"))
    kk = add_parser("kernels", help="registered kernels and schemes; with FAMILY their parameters and settings")
    kk.add_argument("family", nargs="?", help="e.g. aggregation, breakage_selection, growth_scheme")
    kk.set_defaults(func=_cmd("info", "cmd_kernels"))
    mt = add_parser("materials", help="the catalogue of solid materials; with NAME its values and sources")
    mt.add_argument("name", nargs="?")
    mt.set_defaults(func=_cmd("info", "cmd_materials"))
    d = add_parser("describe", help="a scene's parameters: value, SI unit, default, bounds, source, description")
    d.add_argument("scene")
    d.add_argument("--format", choices=["table", "csv", "json"], default="table",
                   help="table (every column, never truncated), csv or json")
    d.set_defaults(func=_cmd("info", "cmd_describe"))
    g = add_parser("docs", help="write the generated reference pages (units, kernels) into a docs folder")
    g.add_argument("--write", dest="dir", metavar="DIR", default="docs", help="docs folder (default: docs)")
    g.add_argument("--check", action="store_true", help="only check that the pages are up to date (exit 2 if not)")
    g.add_argument("--quiet", action="store_true")
    g.set_defaults(func=_cmd("info", "cmd_docs"))
    b = add_parser("bench", help="benchmarks: speed against error (never pass/fail on time)")
    b.add_argument("what", choices=["core", "pbm", "pbm2d", "scene", "sweep", "loop", "targets"])
    b.add_argument("--json", action="store_true", help="print JSON records")
    b.add_argument("--repeats", type=int, default=7)
    b.add_argument("--quick", action="store_true",
                   help="a reduced set: " + "; ".join(f"{k}: {v}" for k, v in _QUICK.items()))
    b.add_argument("--no-scipy", action="store_true", help="scene, pbm2d, loop, targets: time granuflow only")
    b.add_argument("--only", action="append", metavar="TARGET",
                   help="targets: measure only this one (repeatable): calibration, contour, classes, two_zone, "
                        "writing, run")
    b.add_argument("--write-json", metavar="FILE", help="targets: also write the records to FILE (JSON)")
    b.add_argument("--quiet", action="store_true", help="no progress lines")
    b.set_defaults(func=_cmd("bench", "cmd_bench"))
    c = add_parser("calibrate", help="staged calibration against experiments; report, tables, parity plots")
    c.add_argument("experiments", help="experiment file (YAML, see granuflow.calibration)")
    c.add_argument("--stages", required=True, help="stage file (YAML): free parameters, bounds, observables")
    c.add_argument("--out", required=True, help="output folder (created)")
    c.add_argument("--workers", type=int, help="threads: experiments in parallel, or starts with --starts (default: "
                   "number of cores; the estimates are the same for any number)")
    c.add_argument("--starts", type=int, default=1, help="multi-start: number of starts (the first is the file's)")
    c.add_argument("--spread", type=float, default=1.0, help="multi-start: ± spread in ln units around the start")
    c.add_argument("--seed", type=int, default=0, help="multi-start: random seed")
    c.add_argument("--compare", action="store_true", help="also fit all parameters at once from the same start")
    c.add_argument("--error-estimate", action="store_true",
                   help="the model's numerical error at every sample (finer size grids, tighter tolerance) in "
                        "predictions.csv and, against sigma, in fit.csv")
    c.add_argument("--no-plots", action="store_true", help="write the report and tables without the parity PNGs")
    c.add_argument("--no-progress", action="store_true", help="no progress bar (default: only on a terminal)")
    c.add_argument("--quiet", action="store_true", help="no output but warnings and errors (and no progress bar)")
    c.set_defaults(func=_cmd("calibrate", "cmd_calibrate"))
    return p, sub


def _parser_for(argv: list[str]):
    """(parser, subparsers) for this command line: of the command it names, else of all (help and errors list
    them)."""
    named = _named_command(argv)
    p, sub = _parser(named)
    return (p, sub) if named is None or named in sub.choices else _parser(None)


def entry() -> None:
    """The `granuflow` command as a process (``python -m granuflow``, the installed script): :func:`main`, then an exit
    that skips the interpreter's teardown. Freeing every module and the core's scenes one by one took 8-10 ms, a tenth
    of a plain run (issue 32); the operating system reclaims the memory at once. Only when the command left no other
    thread running (a thread pool or a Dask client exits the ordinary way, waiting for its threads); the atexit
    handlers run and the output streams are flushed first, so nothing a command or a plugin registered is lost."""
    code = main()
    threading = sys.modules.get("threading")  # not imported: no thread started from Python
    if threading is not None and threading.active_count() > 1:
        sys.exit(code)
    import atexit

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a reader that went away, a stream already closed: nothing left to say
            pass
    os._exit(code if isinstance(code, int) else 1)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    p, sub = _parser_for(argv)
    if not argv:
        p.error(f"no command given; the commands are {', '.join(sub.choices)} (granuflow COMMAND --help for each)")
    args = p.parse_args(argv)

    from .. import _core

    try:
        _load_plugins(args.plugin)
        code = args.func(args)
        if code == 0 and args.cmd in _PROVENANCE:
            from .provenance import write_provenance

            write_provenance(args, argv)
        return code
    except (_core.ConfigError, FileNotFoundError) as e:
        print(f"granuflow: bad input: {one_line(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (IsADirectoryError, NotADirectoryError, PermissionError, UnicodeError) as e:
        # Every file the commands read goes through granuflow.textfile, which names the file and the key; this is
        # the net under it: still one line naming the file (OSError says which), never a traceback.
        print(f"granuflow: bad input: {one_line(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RecursionError:
        print("granuflow: bad input: an input nested too deeply to read (YAML files allow 64 levels)", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (_core.SolverError, _core.CalibrationError) as e:
        what = "balance failure" if hasattr(e, "balance") else "solver failure"  # result.BalanceError
        print(f"granuflow: {what}: {one_line(e)}", file=sys.stderr)
        return EXIT_SOLVER
    except KeyboardInterrupt:  # Ctrl-C: the core's runs stop within about 0.1 s (interrupt_poll.hpp)
        print("granuflow: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # the reader went away (`granuflow describe SCENE | head`): stop quietly, and keep Python from
        # reporting the failed flush of stdout at exit
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
