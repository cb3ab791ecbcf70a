"""Importing granuflow sets glibc's malloc to keep what a solve frees for the next one (python/src/allocator.cpp):
repeated solves reuse their pages instead of faulting fresh ones, and a user's own malloc settings win."""
import platform
import subprocess
import sys

import pytest

from conftest import SCENE, package_env

# In a fresh process after importing granuflow: (1) a 16 MiB block is allocated, written, freed, allocated again and
# written again, counting the minor page faults of the second writing (glibc's defaults serve the first block with a
# mapping of its own and return it to the kernel when it is freed, so the second one faults in afresh); (2) solves of
# the headline scene at 80 classes (1.2 MB of result arrays each) after two warm-ups, counting faults per solve.
PROBE = f"""
import ctypes, resource, granuflow as gf, granuflow._core as core
faults = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_minflt
libc = ctypes.CDLL(None)
libc.malloc.restype, libc.malloc.argtypes, libc.free.argtypes = ctypes.c_void_p, [ctypes.c_size_t], [ctypes.c_void_p]
size = 16 << 20
p = libc.malloc(size); ctypes.memset(p, 1, size); libc.free(p)
p = libc.malloc(size); f0 = faults(); ctypes.memset(p, 1, size); block = faults() - f0; libc.free(p)
fs = gf.load({SCENE!r}).with_settings({{"particles.classes": 80}})
run = lambda: fs.simulate(warn=False, grid_check=False, accuracy=False)
d50 = [run().summary["d50_um"] for _ in range(2)]
f0 = faults()
for _ in range(8):
    d50.append(run().summary["d50_um"])
print(core.allocator_tuned(), block, (faults() - f0) / 8, len(set(d50)), d50[0])
"""


def probe(**env):
    p = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=120,
                       env=package_env(**env))
    assert p.returncode == 0, p.stderr
    tuned, block, per_solve, distinct, d50 = p.stdout.split()
    assert distinct == "1"  # every solve gives the same answer to the bit
    return tuned == "True", int(block), float(per_solve), float(d50)


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's malloc")
def test_freed_memory_is_reused_unless_the_user_configured_malloc():
    tuned, block, per_solve, d50 = probe()
    assert tuned
    assert block < 64, block  # 4096 pages written again without faulting them in
    assert per_solve < 20, per_solve  # glibc's defaults: up to ~320 per solve, as the heap's layout falls
    plain, plain_block, _, plain_d50 = probe(GRANUFLOW_MALLOC_TUNING="0")
    assert not plain
    assert plain_block > 3000, plain_block  # the same block faulted in afresh
    assert d50 == plain_d50  # the allocator changes where memory comes from, never a result
    # a glibc setting of the user's own leaves the allocator as the user set it
    assert not probe(MALLOC_TOP_PAD_="131072")[0]
    assert not probe(GLIBC_TUNABLES="glibc.malloc.trim_threshold=1000000")[0]
    # an unrelated tunable does not count as configuring malloc
    assert probe(GLIBC_TUNABLES="glibc.rtld.optional_static_tls=1024")[0]


def test_a_malformed_choice_warns_and_changes_nothing():
    code = ("import warnings; warnings.simplefilter('always')\n"
            "with warnings.catch_warnings(record=True) as w:\n"
            "    import granuflow._core as core\n"
            "print(core.allocator_tuned()); print([str(x.message) for x in w if x.category is RuntimeWarning])")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                       env=package_env(GRANUFLOW_MALLOC_TUNING="off"))
    assert p.returncode == 0, p.stderr
    tuned, warned = p.stdout.splitlines()
    assert tuned == "False"
    assert "GRANUFLOW_MALLOC_TUNING='off'" in warned and "expected 0" in warned and " or 1 " in warned, warned
