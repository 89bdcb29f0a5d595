"""What the perf gate measures (scripts/perf.py): the deterministic metrics (xb_perf_metrics), the
Google Benchmark runs (xb_microbench), the machine and commit they ran on, and the timed metrics
as ratios to the same run's triad reference or SpMV."""
import json
import os
import platform
import socket
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TRIAD_PREFIX = "triad/"
SPMV_PREFIX = "spmv/"


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw).stdout.strip()


def git_info():
    try:
        sha = sh(["git", "rev-parse", "--short=12", "HEAD"], cwd=ROOT)
        dirty = bool(sh(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT))
        subject = sh(["git", "log", "-1", "--format=%s"], cwd=ROOT)
        when = sh(["git", "log", "-1", "--format=%cI"], cwd=ROOT)
    except (subprocess.CalledProcessError, FileNotFoundError):
        return {"sha": "unknown", "dirty": True, "subject": "", "commit_time": ""}
    return {"sha": sha, "dirty": dirty, "subject": subject, "commit_time": when}


def machine_description(build):
    m = {
        "hostname": socket.gethostname(),
        "platform": platform.platform(),
        "machine": platform.machine(),
        "python": platform.python_version(),
        "nproc": os.cpu_count(),
        "omp_num_threads": os.environ.get("OMP_NUM_THREADS", ""),
    }
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    m["cpu"] = line.split(":", 1)[1].strip()
                    break
        with open("/proc/meminfo") as f:
            m["memory_kib"] = int(f.readline().split()[1])
        with open("/proc/loadavg") as f:
            m["load_average"] = [float(v) for v in f.read().split()[:3]]
    except OSError:
        pass
    cache = os.path.join(build, "CMakeCache.txt")
    if os.path.exists(cache):
        with open(cache) as f:
            for line in f:
                for key in ("CMAKE_CXX_COMPILER:", "CMAKE_BUILD_TYPE:", "XB_WITH_HYPRE:", "XB_WITH_MUELU:"):
                    if line.startswith(key):
                        m[key.rstrip(":").lower()] = line.split("=", 1)[1].strip()
        if "cmake_cxx_compiler" in m:
            try:
                m["compiler_version"] = sh([m["cmake_cxx_compiler"], "--version"]).splitlines()[0]
            except (subprocess.CalledProcessError, OSError):
                pass
    return m


def tool(build, name):
    exe = os.path.join(build, name)
    if not os.path.exists(exe):
        sys.exit(f"perf: {exe} not found (build it: ninja -C {build} {name})")
    return exe


def run_json(name, command, **run_args):
    """Runs command(out) with `out` a temporary JSON file and returns what it wrote; a failure exits
    with the tail of its stderr when that was captured."""
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as t:
        out = t.name
    try:
        r = subprocess.run(command(out), cwd=ROOT, **run_args)
        if r.returncode != 0:
            detail = f":\n{r.stderr[-4000:]}" if r.stderr else ""
            sys.exit(f"perf: {name} failed (exit {r.returncode}){detail}")
        with open(out) as f:
            return json.load(f)
    finally:
        os.unlink(out)


def run_metrics(build, extra_args=()):
    exe = tool(build, "xb_perf_metrics")
    return run_json("xb_perf_metrics", lambda out: [exe, "--out", out, *extra_args],
                    text=True, stderr=subprocess.PIPE)


def run_benchmarks(build, short, threads, bench_filter=None):
    exe = tool(build, "xb_microbench")

    def command(out):
        cmd = [exe, f"--benchmark_out={out}", "--benchmark_out_format=json",
               "--xb_sizes=" + ("small" if short else "all"),
               "--benchmark_min_time=" + ("0.02" if short else "0.1"), "--benchmark_repetitions=3"]
        return cmd + ([f"--benchmark_filter={bench_filter}"] if bench_filter else [])

    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads))
    # The console table goes to stderr so that it is seen as it runs.
    return run_json("xb_microbench", command, stdout=sys.stderr, env=env)


def timing_field(threads):
    """Single-threaded: the benchmark thread's CPU time (robust on a loaded machine); else wall."""
    return "cpu_time" if threads == 1 else "real_time"


def fastest(gbench, field):
    """Each benchmark name's fastest repetition (the least disturbed by other load); {} if none."""
    best = {}
    for b in (gbench or {}).get("benchmarks", []):
        if b.get("run_type", "iteration") != "iteration" or b.get("error_occurred"):
            continue
        name = b.get("run_name", b["name"])
        best[name] = min(best.get(name, float("inf")), b[field])
    return best


def timed_ratios(gbench, field="cpu_time"):
    """Benchmark times over the triad's, per benchmark name ({} without a triad). With
    repetitions, each name's fastest repetition counts (the least disturbed by other load)."""
    best = fastest(gbench, field)
    triad = [v for k, v in best.items() if k.startswith(TRIAD_PREFIX)]
    if not triad or min(triad) <= 0:
        return {}
    ref = min(triad)
    return {k: v / ref for k, v in best.items() if not k.startswith(TRIAD_PREFIX)}


def spmv_unit_ratios(gbench, field="cpu_time"):
    """Each kernel's time over the SpMV of the same scene (the benchmark name's last two parts,
    e.g. cloth_hang/r16) in this run, fastest repetition of each: kernel costs in SpMV units."""
    best = fastest(gbench, field)
    spmv = {k[len(SPMV_PREFIX):]: v for k, v in best.items() if k.startswith(SPMV_PREFIX) and v > 0}
    out = {}
    for k, v in best.items():
        case = "/".join(k.split("/")[-2:])
        if case in spmv and not k.startswith(SPMV_PREFIX) and not k.startswith(TRIAD_PREFIX):
            out[k] = v / spmv[case]
    return out
