"""The command line without a command lists the commands; counts beyond any sane run are refused at once; a docs
folder that cannot be written is one line naming --write."""
import os
import time

import pytest

from granuflow import cli


def _main(capsys, argv):
    capsys.readouterr()
    t0 = time.perf_counter()
    code = cli.main(argv)
    return code, capsys.readouterr().err, time.perf_counter() - t0


def test_no_command_lists_the_commands(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main([])
    err = capsys.readouterr().err
    assert e.value.code == 2
    assert len(err.strip().splitlines()) == 1, err
    for name in ("run", "steady", "sweep", "contour", "calibrate", "bench"):
        assert name in err, err
    assert "required: cmd" not in err


ONE_COMMAND = [(["run", "x"], "run"), (["--plugin", "a.so", "--plugin=b.so", "sweep"], "sweep"),
               (["rn", "x"], None), (["--plug", "run", "run"], None), (["-h"], None), (["--version"], None)]


@pytest.mark.parametrize("argv, built", ONE_COMMAND)
def test_only_the_named_command_has_its_parser_built(capsys, argv, built):
    # issue 32: a run builds its own command's parser only; anything else all of them, so that help and errors
    # list them ("rn": invalid choice, choose from ...)
    _, sub = cli._parser_for(argv)
    assert list(sub.choices) == ([built] if built else list(cli._parser(None)[1].choices))
    assert len(sub.choices) == (1 if built else 13)
    if argv[0] == "rn":
        with pytest.raises(SystemExit):
            cli.main(argv)
        assert "invalid choice: 'rn' (choose from 'run', 'steady'" in capsys.readouterr().err


@pytest.mark.parametrize("repeats", ["99999999999999999999", "10001"])
def test_bench_repeats_beyond_any_sane_run_are_refused_at_once(capsys, repeats):
    code, err, seconds = _main(capsys, ["bench", "scene", "--repeats", repeats])
    assert code == 2, err
    assert f"--repeats = {repeats}: expected a number <= 10000" in err
    assert seconds < 5


def test_bench_repeats_below_one_name_both_bounds(capsys):
    code, err, _ = _main(capsys, ["bench", "core", "--repeats", "0"])
    assert code == 2 and "--repeats = 0: expected a number >= 1 and <= 10000" in err, err


@pytest.mark.parametrize("target", ["loop", "file"])
def test_docs_into_a_link_loop_or_onto_a_file_is_one_line_naming_write(tmp_path, capsys, target):
    if target == "loop":
        os.symlink(tmp_path / "b", tmp_path / "a")
        os.symlink(tmp_path / "a", tmp_path / "b")
        where, reason = tmp_path / "a", "symbolic links"
    else:
        (tmp_path / "a").write_text("not a folder\n")
        where, reason = tmp_path / "a", "Not a directory"
    code, err, _ = _main(capsys, ["docs", "--write", str(where), "--quiet"])
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert f"--write {where}: cannot write" in err and reason in err, err
    assert "Traceback" not in err


@pytest.mark.parametrize("columns", [None, "", "0", "abc", "-3", "57", "300"])
def test_help_is_laid_out_at_the_width_shutil_gives(monkeypatch, columns):
    # the command line leaves shutil unimported (issue 32): its own reading of the terminal's width is shutil's
    import argparse
    import shutil

    from granuflow.cli import common

    if columns is None:
        monkeypatch.delenv("COLUMNS", raising=False)
    else:
        monkeypatch.setenv("COLUMNS", columns)
    assert common._columns() == shutil.get_terminal_size().columns
    mine = cli._parser(None)[0]
    plain = cli._parser(None)[0]
    for p in [plain, *plain._subparsers._group_actions[0].choices.values()]:
        p.formatter_class = argparse.HelpFormatter
    assert mine.format_help() == plain.format_help()
    assert mine._subparsers._group_actions[0].choices["run"].format_help() == \
        plain._subparsers._group_actions[0].choices["run"].format_help()


def _mo_file(path, translations: dict) -> None:
    """A GNU gettext catalogue (.mo) holding ``translations``, written the way msgfmt lays it out."""
    import struct

    keys = sorted(translations)
    ids = [k.encode() for k in keys]
    strs = [translations[k].encode() for k in keys]

    def table(strings, at):  # (length, offset) of each string, stored one after the other with a NUL after each
        out = []
        for text in strings:
            out.append((len(text), at))
            at += len(text) + 1
        return out
    start = 7 * 4 + 16 * len(keys)
    offsets, trans = table(ids, start), table(strs, start + sum(len(k) + 1 for k in ids))
    head = struct.pack("7I", 0x950412DE, 0, len(keys), 28, 28 + 8 * len(keys), 0, 0)
    path.write_bytes(head + b"".join(struct.pack("2I", *p) for p in offsets + trans)
                     + b"".join(t + b"\0" for t in ids + strs))


@pytest.mark.parametrize("language", ["xx", "yy"])
def test_argparse_messages_still_go_through_the_locale_catalogue(tmp_path, language):
    # issue 32: the command line looks the catalogue up once instead of on every string argparse builds; a user
    # whose locale has one still reads argparse's messages through it, and one without reads them as written
    import subprocess
    import sys

    (tmp_path / "xx" / "LC_MESSAGES").mkdir(parents=True)
    _mo_file(tmp_path / "xx" / "LC_MESSAGES" / "messages.mo", {"usage: ": "Aufruf: "})
    code = ("import gettext, sys; gettext.bindtextdomain('messages', sys.argv[1]); "
            "import argparse; from granuflow.cli import common; "
            "assert argparse._ is not gettext.gettext; "
            "print(argparse._('usage: ') + '|' + gettext.gettext('usage: ')); "
            "common.Parser(prog='granuflow').print_usage()")
    env = dict(os.environ, LANGUAGE=language, LC_ALL="C")
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    word = "Aufruf: " if language == "xx" else "usage: "
    assert p.stdout.splitlines() == [f"{word}|{word}", f"{word}granuflow [-h]"]
