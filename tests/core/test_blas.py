"""The tracker's one-BLAS-thread section: one thread inside, the process's own count after."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

INSIDE_AND_AFTER = """
from core.blas import blas_threads, one_blas_thread
seen = [blas_threads()]
try:
    with one_blas_thread():
        seen.append(blas_threads())
        raise KeyError
except KeyError:
    seen.append(blas_threads())
print(*seen)
"""


def test_one_blas_thread_inside_and_the_count_given_back_after_an_error():
    env = dict(os.environ, OPENBLAS_NUM_THREADS="2")
    proc = subprocess.run([sys.executable, "-c", INSIDE_AND_AFTER], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["2", "1", "2"]
