#!/usr/bin/env python3
"""Makes the package the build wrote (BUILD/python/xpbd_bench) importable by the python3 running
this, without a second C++ build: a file xpbd_bench-build.pth in its site-packages names
BUILD/python (Python adds such paths to sys.path at start-up). Called by `make build` (so by
`make demo` and `make test`); does nothing when the build has no package (XB_PYTHON=OFF). A
`pip install .` of the package goes to site-packages itself and is found first.

usage: python3 scripts/link_python_package.py BUILD
"""
import os
import sys
import sysconfig


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    path = os.path.abspath(os.path.join(sys.argv[1], "python"))
    if not os.path.isdir(os.path.join(path, "xpbd_bench")):
        return 0
    pth = os.path.join(sysconfig.get_paths()["purelib"], "xpbd_bench-build.pth")
    try:
        if not os.path.exists(pth) or open(pth).read().strip() != path:
            with open(pth, "w") as f:
                f.write(path + "\n")
    except OSError as e:
        print(f"link_python_package: cannot write {pth} ({e}); use PYTHONPATH={path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
