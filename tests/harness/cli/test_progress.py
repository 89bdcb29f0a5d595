#!/usr/bin/env python3
"""Live progress (harness/cli/progress.hpp), a ctest: `run` on a pseudo-terminal redraws one status
line (carriage return + erase) at least three times with an ETA; with stderr piped to a file, or
with --quiet, there is none and the log line is as before.

usage: python3 tests/harness/cli/test_progress.py --binary build/xpbd-bench
"""
import argparse
import os
import pty
import re
import subprocess
import sys
import tempfile

# Several redraws, one every 0.25 s: six frames of a direct solve, ~2 s on a quiet machine (two
# frames took 0.73 s there on one thread: two redraws, too few).
RUN = ["run", "--scene", "squash", "--set", "resolution=10", "--frames", "6", "--solver", "cholmod"]
REDRAW = "\r\x1b[K"


def on_terminal(cmd):
    """(exit code, what the command wrote to its stderr, a pseudo-terminal)."""
    master, slave = pty.openpty()
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    return proc.wait(), b"".join(chunks).decode(errors="replace")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    args = ap.parse_args()
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.h5")
        rc, text = on_terminal([args.binary, *RUN, "--out", out])
        updates = [u for u in text.split(REDRAW)[1:] if re.search(r"frame \d/6, iteration \d+, .*ETA \d+:\d\d", u)]
        if rc != 0 or len(updates) < 3:
            failures.append(f"terminal: exit {rc}, {len(updates)} status lines with an ETA (want >= 3):\n{text!r}")
        if not re.search(r"\r\x1b\[Krun: squash with cholmod \.\.\. (ok|max_iterations) \(", text):
            failures.append(f"terminal: the run's own line does not close the status line:\n{text!r}")

        rc, quiet = on_terminal([args.binary, *RUN, "--quiet", "--out", out])
        if rc != 0 or "\x1b" in quiet or "\r" in quiet.replace("\r\n", "\n"):
            failures.append(f"--quiet on a terminal: exit {rc}, output {quiet!r}")

        with open(os.path.join(tmp, "stderr.txt"), "w+") as log:
            rc = subprocess.run([args.binary, *RUN, "--out", out], stdout=subprocess.DEVNULL, stderr=log).returncode
            log.seek(0)
            piped = log.read()
        if rc != 0 or "\x1b" in piped or "\r" in piped or not re.fullmatch(r"run: squash with cholmod \.\.\. \S+ \(.*\)\n", piped):
            failures.append(f"piped: exit {rc}, stderr {piped!r}")
    for f in failures:
        print("FAIL", f)
    print(f"{3 - len(failures)} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
