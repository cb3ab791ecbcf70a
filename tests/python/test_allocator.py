"""Importing granuflow sets glibc's malloc to keep what a solve frees for the next one (python/src/allocator.cpp):
repeated solves reuse their pages instead of faulting fresh ones, and a user's own malloc settings win."""
import subprocess
import sys

import pytest

from conftest import SCENE, package_env

# Solves of the headline scene at 80 classes (1.2 MB of result arrays each) after two warm-ups; prints whether the
# allocator was tuned and the minor page faults per solve.
FAULTS_PER_SOLVE = f"""
import resource, granuflow as gf, granuflow._core as core
fs = gf.load({SCENE!r}).with_settings({{"particles.classes": 80}})
run = lambda: fs.simulate(warn=False, grid_check=False, accuracy=False)
d50 = [run().summary["d50_um"] for _ in range(2)]
f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(8):
    d50.append(run().summary["d50_um"])
print(core.allocator_tuned(), (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0) / 8, len(set(d50)), d50[0])
"""


def faults_per_solve(**env):
    p = subprocess.run([sys.executable, "-c", FAULTS_PER_SOLVE], capture_output=True, text=True, timeout=120,
                       env=package_env(**env))
    assert p.returncode == 0, p.stderr
    tuned, faults, distinct, d50 = p.stdout.split()
    assert distinct == "1"  # every solve gives the same answer to the bit
    return tuned == "True", float(faults), float(d50)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_repeated_solves_reuse_their_memory_unless_the_user_configured_malloc():
    tuned, faults, d50 = faults_per_solve()
    assert tuned
    # glibc's own behaviour faults the result arrays in afresh: about 300 faults per solve at 80 classes
    plain, plain_faults, plain_d50 = faults_per_solve(GRANUFLOW_MALLOC_TUNING="0")
    assert not plain
    assert plain_faults > 100, plain_faults
    assert faults < 0.1 * plain_faults, (faults, plain_faults)
    assert d50 == plain_d50  # the allocator changes where memory comes from, never a result
    # a glibc setting of the user's own leaves the allocator as the user set it
    assert not faults_per_solve(MALLOC_TOP_PAD_="131072")[0]
    assert not faults_per_solve(GLIBC_TUNABLES="glibc.malloc.trim_threshold=1000000")[0]
    # an unrelated tunable does not count as configuring malloc
    assert faults_per_solve(GLIBC_TUNABLES="glibc.rtld.optional_static_tls=1024")[0]
