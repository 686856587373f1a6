"""
Benchmark: numba compile time of the README's main command (issue 26).

Runs ``gongsynth simulate`` (the built-in default) in this process with a
listener on numba's ``numba:compile`` events and prints, for every dispatcher
compiled, the number of type specialisations and the seconds spent compiling
(exclusive of nested compiles), and the process CPU time of the run.  With an
empty ``NUMBA_CACHE_DIR`` this is the first run's compile bill; run it a second
time with the same directory to check that nothing compiles any more (every
kernel loads from the cache).

``--write-kernels`` (with an empty cache) writes the compile tasks of the run
to `gongsynth.precompile.KERNELS`, the queue a first run's background
compilers share: every gongsynth function compiled that has a numba cache
(called from Python or from another kernel), its signatures, its compile CPU
(exclusive of the cached functions it calls, inclusive of numba's own helpers,
which every process compiles again), and the tasks it calls (from the compiled
code's linked libraries); ordered by the longest chain of compiles from each
task to the end (callees always before their callers).  It prints when two
compilers working through that queue would end (rerun it when a kernel's
arguments change; ``tests/test_precompile.py`` says when).

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


def is_task(disp):
    """Whether a dispatcher is a task of `gongsynth.precompile`: a gongsynth function with a numba cache."""
    from numba.core.caching import NullCache

    func = disp.py_func
    return (func.__module__.startswith("gongsynth.") and "<locals>" not in func.__qualname__
            and not isinstance(disp._cache, NullCache))


class CompileTimes(event.Listener):
    """
    Exclusive compile CPU seconds per dispatcher (nested compiles subtracted), and per task.

    CPU seconds of the compiling thread: compiles run one at a time under numba's lock, so the
    figures hold on a loaded machine, where wall time does not.  ``own``: a task's
    seconds less those of the tasks compiled inside it (numba's helpers stay in).
    """

    def __init__(self):
        self.stack = []
        self.total = collections.defaultdict(float)
        self.own = collections.defaultdict(float)
        self.count = collections.Counter()
        self.dispatchers = []      # in the order their compiles ended (callees first)
        self.stage = {}            # dispatcher -> the chain stage that compiled it first
        self.stages = []           # the stages run so far (the current one last)
        self.work = {}             # stage -> the run's own CPU seconds in it (its compiles not counted)
        self.compiling = 0.0       # CPU seconds of compiles called from Python so far

    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"], time.thread_time(), 0.0, 0.0])

    def on_end(self, ev):
        disp, t0, nested, nested_tasks = self.stack.pop()
        dt = time.thread_time() - t0
        name = f"{disp.py_func.__module__}.{disp.py_func.__qualname__}"
        self.total[name] += dt - nested
        self.count[name] += 1
        task = is_task(disp)
        if task:
            self.own[disp] += dt - nested_tasks
            self.dispatchers.append(disp)
            self.stage.setdefault(disp, self.stages[-1] if self.stages else None)
        if self.stack:
            self.stack[-1][2] += dt
            self.stack[-1][3] += dt if task else nested_tasks
        else:
            self.compiling += dt


def compile_tasks(listener):
    """
    The run's compile tasks for `gongsynth.precompile.KERNELS`, in queue order (see the module's text).
    """
    dispatchers = list(dict.fromkeys(listener.dispatchers))
    key = {d: (d.py_func.__module__, d.py_func.__qualname__) for d in dispatchers}
    owner = {id(cres.library): d for d in dispatchers for cres in d.overloads.values()}
    calls = {d: sorted({key[owner[id(lib)]] for cres in d.overloads.values()
                        for lib in cres.library._linking_libraries if id(lib) in owner} - {key[d]})
             for d in dispatchers}
    cost = {key[d]: listener.own[d] for d in dispatchers}
    # The longest chain from each task to the run's end: its callers' compiles, or the run's own
    # work from the stage that needs it on (a kernel needed early leaves more of the run waiting).
    stages = listener.stages
    tail = {d: sum(listener.work.get(s, 0.0) for s in stages[stages.index(listener.stage[d]):])
            if listener.stage[d] in stages else 0.0 for d in dispatchers}
    callers = {key[d]: [key[e] for e in dispatchers if key[d] in calls[e]] for d in dispatchers}
    rank = {}

    def chain(d):
        if key[d] not in rank:
            rank[key[d]] = cost[key[d]] + max([tail[d]] + [chain(e) for e in dispatchers
                                                           if key[e] in callers[key[d]]])
        return rank[key[d]]

    order = sorted(dispatchers, key=lambda d: -chain(d))
    index = {key[d]: n for n, d in enumerate(order)}
    return [{"module": key[d][0], "function": key[d][1],
             "signatures": [[str(t) for t in sig] for sig in d.signatures],
             "cpu_s": round(cost[key[d]], 2), "calls": sorted(index[c] for c in calls[d]),
             "stage": listener.stage[d]} for d in order]


def simulate_queue(tasks, workers=2):
    """When each of ``workers`` compilers taking tasks off the queue (as `gongsynth.precompile` does) ends."""
    free, done, clock = list(range(len(tasks))), {}, [0.0] * workers
    while free:
        w = min(range(workers), key=clock.__getitem__)
        ready = [n for n in free if all(done.get(c, float("inf")) <= clock[w] for c in tasks[n]["calls"])]
        if not ready:      # the other compiler's task first
            clock[w] = min(t for t in done.values() if t > clock[w])
            continue
        done[ready[0]] = clock[w] = clock[w] + tasks[ready[0]]["cpu_s"]
        free.remove(ready[0])
    return clock


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--out", default=None, help="output folder (default: a temporary one)")
    parser.add_argument("--write-kernels", action="store_true",
                        help="write gongsynth.precompile.KERNELS from this run (empty numba cache only)")
    args, rest = parser.parse_known_args(argv)
    listener = CompileTimes()
    t0, c0 = time.perf_counter(), time.process_time()
    from gongsynth import chain, cli

    run_stage = chain.Stage.__call__

    def stage_call(stage, state):
        listener.stages.append(stage.name)
        cpu, compiling = time.process_time(), listener.compiling
        try:
            return run_stage(stage, state)
        finally:
            listener.work[stage.name] = time.process_time() - cpu - (listener.compiling - compiling)

    chain.Stage.__call__ = stage_call
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

        if not listener.dispatchers:
            raise SystemExit("--write-kernels: nothing compiled; run with an empty NUMBA_CACHE_DIR")
        tasks = compile_tasks(listener)
        precompile.KERNELS.write_text(json.dumps({
            "about": "gongsynth.precompile.KERNELS, written by benchmarks/bench_compile.py --write-kernels",
            "compile_cpu_s": round(sum(t["cpu_s"] for t in tasks), 2), "stages": listener.stages,
            "tasks": tasks}, indent=1) + "\n")
        print(f"wrote {precompile.KERNELS}: {len(tasks)} tasks")
    if listener.dispatchers:
        tasks = compile_tasks(listener)
        from gongsynth import precompile

        ends = simulate_queue(tasks, precompile.WORKERS)
        print(f"{len(tasks)} tasks, {sum(t['cpu_s'] for t in tasks):.2f} s CPU: "
              f"{len(ends)} compilers sharing the queue would end after "
              f"{', '.join(f'{e:.2f}' for e in ends)} s")


if __name__ == "__main__":
    sys.exit(main())
