"""What every command shares: exit codes, one-line errors, option checks, output that survives a closed pipe."""
from __future__ import annotations

import argparse
import gettext
import math
import os
import sys

from .. import _core
from ..quantity import parse_time

ConfigError = _core.ConfigError
EXIT_BAD_INPUT = 2
EXIT_SOLVER = 3
EXIT_INTERRUPTED = 130  # Ctrl-C, as a shell reports a process SIGINT ended (128 + 2)


def _columns() -> int:
    """shutil.get_terminal_size().columns, without importing shutil (and the compression modules it imports: ~4 ms
    of every run, issue 32) for the help layout argparse sets up on each option: COLUMNS when a positive whole
    number, else the width of the terminal on stdout, else 80."""
    try:
        columns = int(os.environ["COLUMNS"])
    except (KeyError, ValueError):
        columns = 0
    if columns > 0:
        return columns
    try:
        return os.get_terminal_size(sys.__stdout__.fileno()).columns or 80
    except (AttributeError, ValueError, OSError):
        return 80


def _catalogue_gettext():
    """gettext.gettext of this process's locale, its catalogue looked up once: argparse passes each string it
    builds through gettext.gettext, which searches the locale folders for a catalogue on every call (about 0.5 ms
    each, 3 ms of every ``granuflow run``, issue 32). The catalogue a lookup finds (or that none exists) does not
    change while the process runs, so the messages are the same."""
    domain = gettext.textdomain()
    try:
        return gettext.translation(domain, gettext.bindtextdomain(domain)).gettext
    except OSError:  # no catalogue: gettext.gettext returns each message as it is
        return str


argparse._ = _catalogue_gettext()


class HelpFormatter(argparse.HelpFormatter):
    def __init__(self, prog, indent_increment=2, max_help_position=24, width=None):
        super().__init__(prog, indent_increment, max_help_position, _columns() - 2 if width is None else width)


class Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message):  # argparse exits 2 too, but with a usage block; keep it to one line
        print(f"granuflow: {message}", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)


def parse_seconds(text: str, option: str = "--t-end") -> float:
    """A run's end time from the command line (s, or with a time unit): finite and > 0. An empty value is an
    error, not "the scene's" (leave the option out for that)."""
    t = parse_time(text, option)
    if not (math.isfinite(t) and t > 0):
        raise ConfigError(f"{option} = '{text}': t_end = {t:g} s violates t_end > 0 (an end time such as '60 min'; "
                          f"leave {option} out for the scene's)")
    return t


def parse_times(text: str, option: str) -> list[float]:
    """A comma-separated list of times (s, or with a time unit) from the command line, each > 0."""
    times = [parse_time(item.strip(), option) for item in text.split(",") if item.strip()]
    if not times:
        raise ConfigError(f"{option} = '{text}': expected times such as '10 min,30 min'")
    return times


def parse_sets(items) -> dict:
    """``--set unit.name=value`` options as {name: value text} (a parameter, or a setting, which rebuilds the
    flowsheet: granuflow.structure.apply); a malformed one is bad input. Quotes around the value are the shell's
    or the user's: ``--set 'particles.d_max="3 mm"'`` gives 3 mm."""
    overrides = {}
    for item in items or []:
        if "=" not in item:
            raise ConfigError(f"--set '{item}': expected unit.param=value or unit.setting=value")
        name, value = item.split("=", 1)
        value = value.strip()
        if len(value) >= 2 and value[0] == value[-1] and value[0] in "\"'":
            value = value[1:-1].strip()
        overrides[name.strip()] = value
    return overrides


def check_at_least(option: str, value, lower, upper=None) -> None:
    """A number from the command line within [lower, upper]: a count beyond any sane run (repeats, starts, workers)
    is a typo, refused before anything runs rather than run without end."""
    if value is not None and not value >= lower:
        raise ConfigError(f"{option} = {value}: expected a number >= {lower}" +
                          (f" and <= {upper}" if upper is not None else ""))
    if value is not None and upper is not None and not value <= upper:
        raise ConfigError(f"{option} = {value}: expected a number <= {upper}")


def check_workers(workers) -> None:
    check_at_least("--workers", workers, 1, 1024)


def check_out_dir(out: str, option: str = "--out") -> None:
    """The output folder, before anything runs: an existing folder or a path that can be created (not an existing
    file), that this process can write to: a probe file is written and removed in the folder, or where it would be
    created (nothing is created for a run that then refuses its input). An answer computed for an hour must not be
    lost to a typo."""
    if not out:
        raise ConfigError(f"{option} = '': expected a folder to write to")
    if os.path.exists(out) and not os.path.isdir(out):
        raise ConfigError(f"{option} = '{out}': an existing file, not a folder (give a folder to write to)")
    parent = out
    while parent and not os.path.exists(parent):
        parent = os.path.dirname(parent.rstrip(os.sep))
    if parent and not os.path.isdir(parent):
        raise ConfigError(f"{option} = '{out}': '{parent}' is a file, not a folder (give a folder to write to)")
    # os.open, not tempfile: that module (and the random one it imports) would cost every run's start-up
    for k in range(100):
        probe = os.path.join(parent or ".", f".granuflow-write-check-{os.getpid()}-{k}")
        try:
            os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        except FileExistsError:  # a probe left by a killed run with this process id
            continue
        except OSError as e:
            raise ConfigError(f"{option} = '{out}': cannot write there ({e.strerror}); give a folder this user can "
                              "write to") from None
        os.unlink(probe)
        return


def json_value(v):
    """A value JSON can hold: NumPy scalars as Python numbers, NaN and inf as null."""
    if hasattr(v, "item"):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def with_unit_headers(df):
    """A copy of ``df`` whose headers carry the units in ``df.attrs["units"]`` (``bed_moisture [kg/kg]``;
    ``d50_um`` stays as it is), for CSV files."""
    from ..outputs import header

    units = df.attrs.get("units", {})
    return df.rename(columns={c: header(c, units[c]) for c in df.columns if units.get(c)})


def one_line(e: BaseException) -> str:
    return " ".join(str(e).split())


def progress_option(args) -> bool | None:
    """The progress bar: off with --quiet or --no-progress, else only on a terminal (None)."""
    return False if getattr(args, "quiet", False) or getattr(args, "no_progress", False) else None
