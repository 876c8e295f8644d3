"""Fleet throughput on Dask (issue 20): robot-sessions per second with 1 and 2 local worker processes, the
overhead per task against `omnical train` on the same session, and the peak memory of a worker.

    python benches/fleet.py [--robots 8] [--sessions 4] [--workdir /tmp/omnical-fleet-bench]

Needs the wheel installed (`pip install ".[fleet]"`, a release build). Prints a Markdown table for
benches/README.md. The fleet is `omnical.fleet.simulate_fleet` (36 runs of 2 s per session, as the tests'
but bigger); diagnosis is off (`diagnose="none"`) so that the figures are the training's, and timed once
apart per session.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from omnical import _omnical, fleet


def peak_rss_mb() -> float:
    """This process's peak resident set size [MB] (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--robots", type=int, default=8)
    p.add_argument("--sessions", type=int, default=4)
    p.add_argument("--workdir", default="/tmp/omnical-fleet-bench")
    a = p.parse_args()
    import distributed

    work = Path(a.workdir)
    shutil.rmtree(work, ignore_errors=True)
    root = work / "fleet"
    t = time.perf_counter()
    fleet.simulate_fleet(root, a.robots, a.sessions, seed=0)
    print(f"simulated {a.robots} x {a.sessions} robot-sessions in {time.perf_counter() - t:.1f} s", file=sys.stderr)
    sessions = fleet.find_sessions(root)
    n = len(sessions)

    # Direct: `omnical train` as a command per session (process start, loading, fit, file), and in process.
    exe = Path(sys.executable).parent / "omnical"
    cmd_s, inproc_s = [], []
    for s in sessions:
        args = fleet.train_args(s, str(work / "direct.toml"), preset="default", seed=0, model="ik", extra=())
        t = time.perf_counter()
        subprocess.run([str(exe), "train", *args, "--quiet"], check=True, capture_output=True)
        cmd_s.append(time.perf_counter() - t)
        t = time.perf_counter()
        _omnical.train_files(args)
        inproc_s.append(time.perf_counter() - t)
    diag_s = []
    for s in sessions[: min(4, n)]:
        args = fleet.train_args(s, str(work / "d.toml"), preset="default", seed=0, model="ik", extra=())
        _omnical.train_files(args)
        t = time.perf_counter()
        fleet.diagnose_session(s, str(work / "d.toml"))
        diag_s.append(time.perf_counter() - t)

    results = []
    for workers in (1, 2):
        threads = max(1, (os.cpu_count() or 1) // workers)
        cluster = distributed.LocalCluster(
            n_workers=workers, processes=True, threads_per_worker=1, dashboard_address=None,
            env={"RAYON_NUM_THREADS": str(threads)},
        )
        client = distributed.Client(cluster)
        client.submit(os.getpid, pure=False).result()  # workers up and importable before timing
        t = time.perf_counter()
        r = fleet.calibrate_fleet(root, work / f"out{workers}", client=client, diagnose="none", progress=False)
        wall = time.perf_counter() - t
        assert not r.errors, r.errors
        rss = client.run(peak_rss_mb)
        task_s = [row["seconds"] for row in r.rows]
        results.append((workers, threads, wall, statistics.mean(task_s), max(rss.values())))
        client.close()
        cluster.close()

    train_mean = statistics.mean(inproc_s)
    print(f"\n{n} robot-sessions ({a.robots} robots x {a.sessions} sessions, 36 runs of 2 s each), preset default\n")
    print("| run | wall | robot-sessions/s | per task (worker) | peak RSS per worker |")
    print("|---|---|---|---|---|")
    print(f"| `omnical train` command per session, serial | {sum(cmd_s):.1f} s | {n / sum(cmd_s):.2f} | {statistics.mean(cmd_s):.3f} s | – |")
    print(f"| `train_files` in one process, serial ({os.cpu_count()} rayon threads) | {sum(inproc_s):.1f} s | {n / sum(inproc_s):.2f} | {train_mean:.3f} s | {peak_rss_mb():.0f} MB (client) |")
    for workers, threads, wall, task, rss in results:
        print(f"| fleet, {workers} worker process(es) x {threads} rayon thread(s) | {wall:.1f} s | {n / wall:.2f} | {task:.3f} s | {rss:.0f} MB |")
    w1 = results[0]
    print(f"\nOverhead per task (1 worker: wall / sessions - in-process train): {1000 * (w1[2] / n - train_mean):.0f} ms")
    print(f"diagnose per session (whole catalogue, in process): {statistics.mean(diag_s):.2f} s")


if __name__ == "__main__":
    main()
