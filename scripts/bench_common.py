"""What the bench scripts share: sizes like 1.5G, and one child's time and peak memory."""
import contextlib
import os
import shutil
import subprocess
import tempfile
import time

UNITS = {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def parse_size(text):
    """Bytes of a --memory-limit as `lightstage solve` reads it: auto (half the machine's), bytes, 1.5G."""
    if text == "auto":
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2
    if text[-1].upper() in UNITS:
        return int(float(text[:-1]) * UNITS[text[-1].upper()])
    return int(text)


def run(cmd):
    """Runs cmd; returns (seconds, that child's own peak RSS in bytes, stdout)."""
    start = time.monotonic()
    with tempfile.TemporaryFile(mode="w+") as out:
        child = subprocess.Popen(cmd, stdout=out)
        _, status, usage = os.wait4(child.pid, 0)  # the child's own rusage, not every child's maximum
        child.returncode = os.waitstatus_to_exitcode(status)
        seconds = time.monotonic() - start
        if child.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)}: exit status {child.returncode}")
        out.seek(0)
        return seconds, usage.ru_maxrss * 1024, out.read()


@contextlib.contextmanager
def work_folder(work, keep, prefix):
    """Yields --work, or a new temporary folder that is removed afterwards unless --keep."""
    folder = work or tempfile.mkdtemp(prefix=prefix)
    os.makedirs(folder, exist_ok=True)
    try:
        yield folder
    finally:
        if not keep and not work:
            shutil.rmtree(folder, ignore_errors=True)
