"""The command line without a command lists the commands; counts beyond any sane run are refused at once."""
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


@pytest.mark.parametrize("repeats", ["99999999999999999999", "10001"])
def test_bench_repeats_beyond_any_sane_run_are_refused_at_once(capsys, repeats):
    code, err, seconds = _main(capsys, ["bench", "scene", "--repeats", repeats])
    assert code == 2, err
    assert f"--repeats = {repeats}: expected a number <= 10000" in err
    assert seconds < 5


def test_bench_repeats_below_one_name_both_bounds(capsys):
    code, err, _ = _main(capsys, ["bench", "core", "--repeats", "0"])
    assert code == 2 and "--repeats = 0: expected a number >= 1 and <= 10000" in err, err
