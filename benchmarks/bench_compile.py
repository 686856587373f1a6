"""
Benchmark: numba compile time of the README's main command (issue 26).

Runs ``gongsynth simulate`` (the built-in default) in this process with a
listener on numba's ``numba:compile`` events and prints, for every dispatcher
compiled, the number of type specialisations and the seconds spent compiling
(exclusive of nested compiles), and the process CPU time of the run.  With an
empty ``NUMBA_CACHE_DIR`` this is the first run's compile bill; run it a second
time with the same directory to check that nothing compiles any more (every
kernel loads from the cache).

``--write-kernels`` (with an empty cache) writes the kernels compiled from
Python, their argument types and their compile times, split into two groups of
about equal compile time, to `gongsynth.precompile.KERNELS`: the list a first
run's background compilers work through (rerun it when a kernel's arguments
change; ``tests/test_precompile.py`` says when).

Run:  NUMBA_CACHE_DIR=$(mktemp -d) GONGSYNTH_PRECOMPILE=0 python benchmarks/bench_compile.py [--out DIR]
      [--write-kernels] [simulate options]
"""
import argparse
import collections
import json
import sys
import tempfile
import time

from numba.core import event


class CompileTimes(event.Listener):
    """
    Exclusive compile CPU seconds per dispatcher (nested compiles subtracted).

    CPU seconds of the compiling thread: compiles run one at a time under numba's lock, so the
    figures hold on a loaded machine, where wall time does not.
    """

    def __init__(self):
        self.stack = []
        self.total = collections.defaultdict(float)
        self.count = collections.Counter()
        self.outer = []       # compiles called from Python: [module, function, [types], inclusive s]

    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"], time.thread_time(), 0.0, ev.data["args"]])

    def on_end(self, ev):
        disp, t0, nested, args = self.stack.pop()
        dt = time.thread_time() - t0
        name = f"{disp.py_func.__module__}.{disp.py_func.__qualname__}"
        self.total[name] += dt - nested
        self.count[name] += 1
        if self.stack:
            self.stack[-1][2] += dt
        else:
            func = disp.py_func
            self.outer.append([func.__module__, func.__qualname__, [str(a) for a in args], dt])


def kernel_groups(outer, n=2):
    """
    The outermost compiles in ``n`` groups of about equal compile time (longest first to the
    lighter group), each group in the run's order.
    """
    groups = [[] for _ in range(n)]
    for order, entry in sorted(enumerate(outer), key=lambda e: -e[1][3]):
        min(groups, key=lambda g: sum(e[1][3] for e in g)).append((order, entry))
    return [[entry[:3] for _, entry in sorted(group)] for group in groups if group]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--out", default=None, help="output folder (default: a temporary one)")
    parser.add_argument("--write-kernels", action="store_true",
                        help="write gongsynth.precompile.KERNELS from this run (empty numba cache only)")
    args, rest = parser.parse_known_args(argv)
    listener = CompileTimes()
    t0, c0 = time.perf_counter(), time.process_time()
    from gongsynth import cli

    with event.install_listener("numba:compile", listener):
        with tempfile.TemporaryDirectory() as tmp:
            cli.main(["simulate", "--out", args.out or tmp, *rest])
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(f"\n{'dispatcher':70s} {'sigs':>4s} {'compile CPU s':>9s}")
    for name, sec in sorted(listener.total.items(), key=lambda kv: -kv[1]):
        print(f"{name:70s} {listener.count[name]:4d} {sec:9.2f}")
    print(f"{'total':70s} {sum(listener.count.values()):4d} {sum(listener.total.values()):9.2f}")
    print(f"run: {wall:.1f} s wall, {cpu:.1f} s CPU (this process)")
    if args.write_kernels:
        from gongsynth import precompile

        if not listener.outer:
            raise SystemExit("--write-kernels: nothing compiled; run with an empty NUMBA_CACHE_DIR")
        groups = kernel_groups([e for e in listener.outer if e[0].startswith("gongsynth.")])
        costs = {tuple(e[:2]): round(e[3], 2) for e in listener.outer}
        precompile.KERNELS.write_text(json.dumps({
            "about": "gongsynth.precompile.KERNELS, written by benchmarks/bench_compile.py --write-kernels",
            "compile_cpu_s": [round(sum(costs[tuple(e[:2])] for e in g), 2) for g in groups],
            "groups": groups}, indent=1) + "\n")
        print(f"wrote {precompile.KERNELS}: groups of {[len(g) for g in groups]} kernels")


if __name__ == "__main__":
    sys.exit(main())
