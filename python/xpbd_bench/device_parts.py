"""Parts of a file for the device machine (scripts/gpu_check.sh, docs/gpu.md): a device call
carries the working tree (tracked files, untracked files git does not ignore, shared/) together
with the paths it names, at most 64 MiB in all, so each part is at most 64 MiB less the tree.

    python3 -m xpbd_bench.device_parts split FILE DIR [--root ROOT] [--limit-mib 64] [--margin-mib 2]

writes DIR/00/chunk, DIR/01/chunk, ... (each carried alone: `carry=["DIR/00"]`) and prints the
part size; `cat DIR/*/chunk` is FILE again. It fails, naming the sizes, when the tree leaves less
than 1 MiB for a part.
"""
import argparse
import os
import subprocess
import sys

MIB = 1 << 20


def tree_bytes(root):
    """Bytes of what a device call carries besides its named paths: the files git tracks or would
    track (not ignored) under root, and root/shared/ where there is one."""
    out = subprocess.run(["git", "-C", root, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                         check=True, capture_output=True).stdout
    paths = {os.path.join(root, name) for name in filter(None, out.decode().split("\0"))}
    shared = os.path.join(root, "shared")
    if os.path.isdir(shared) and not os.path.islink(shared):  # all of it, ignored or not
        paths |= {os.path.join(d, f) for d, _, files in os.walk(shared) for f in files}
    # A deleted tracked file is not carried.
    return sum(os.path.getsize(p) for p in paths if os.path.isfile(p) and not os.path.islink(p))


def part_bytes(tree, limit=64 * MIB, margin=2 * MIB):
    """The largest part that fits beside the tree (and a margin for the tree's growth), in whole MiB."""
    room = (limit - tree - margin) // MIB * MIB
    if room < MIB:
        raise ValueError(f"the working tree is {tree / MIB:.1f} MiB: with a {margin / MIB:g} MiB margin it leaves "
                         f"no room for a part within {limit / MIB:g} MiB")
    return room


def split(path, out_dir, part):
    """FILE into out_dir/NN/chunk of at most `part` bytes each; returns the part paths."""
    os.makedirs(out_dir, exist_ok=True)
    paths = []
    with open(path, "rb") as f:
        while True:
            data = f.read(part)
            if not data and paths:
                break
            d = os.path.join(out_dir, f"{len(paths):02d}")
            os.makedirs(d, exist_ok=True)
            with open(os.path.join(d, "chunk"), "wb") as g:
                g.write(data)
            paths.append(os.path.join(d, "chunk"))
            if len(data) < part:
                break
    return paths


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m xpbd_bench.device_parts", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("split", help="FILE into DIR/NN/chunk parts that fit beside the tree")
    s.add_argument("file")
    s.add_argument("dir")
    s.add_argument("--root", default=".", help="the working tree that travels (default: .)")
    s.add_argument("--limit-mib", type=float, default=64)
    s.add_argument("--margin-mib", type=float, default=2)
    a = ap.parse_args(argv)
    tree = tree_bytes(a.root)
    try:
        part = part_bytes(tree, int(a.limit_mib * MIB), int(a.margin_mib * MIB))
    except ValueError as e:
        print(f"device_parts: {e}", file=sys.stderr)
        return 1
    paths = split(a.file, a.dir, part)
    print(f"device_parts: {len(paths)} part(s) of at most {part / MIB:g} MiB beside a {tree / MIB:.1f} MiB tree "
          f"(limit {a.limit_mib:g} MiB)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
