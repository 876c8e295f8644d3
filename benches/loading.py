#!/usr/bin/env python3
"""Loading speed (issue 17), printed as a table for benches/README.md: the paper-size simulated set
(`omnical simulate` defaults: 180 training runs of ~12 s, 1,180 JointState + ~48 PoseStamped messages each)
as bare MCAP files, as rosbag2 sqlite3 recordings and as rosbag2 MCAP recordings, read by
`omnical eval DIR` (loading, then the Eq. 6 cost of the design model, which takes ~10 ms) on 1 and 2 worker
threads. Each figure is the median wall time of REPEATS runs of the release binary, with the median CPU time
(user + system) in parentheses: on a shared machine the wall time depends on the load (printed before and
after), the CPU time much less.

    bash benches/loading.sh [DATA_DIR]      (builds the release binary, then runs this)
    LOADING_RT=1 bash benches/loading.sh    (each run under `chrt -f 50`, SCHED_FIFO: on a shared machine the
                                             other processes then wait, and the figures are an idle machine's;
                                             needs root or CAP_SYS_NICE)

Needs a Python with rosbags (scripts/test.sh sets up .venv) to convert the set.
"""

import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPEATS = 7


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


RT = ['chrt', '-f', '50'] if os.environ.get('LOADING_RT') else []


def timed(cmd):
    """Wall and CPU time of one run. s."""
    cmd = RT + cmd
    c, t = cpu_children(), time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t, cpu_children() - c


def load():
    return ', '.join(f'{x:.2f}' for x in os.getloadavg())


def main(binary, data):
    data = Path(data)
    here = Path(__file__).parent
    if not (data / 'train').is_dir():
        subprocess.run([binary, 'simulate', '--out', str(data)], check=True, stdout=subprocess.DEVNULL)
    for storage in ['sqlite3', 'mcap']:
        out = data / f'train_{storage}'
        if not out.is_dir():
            subprocess.run([sys.executable, str(here / 'mcap_to_rosbag2.py'), str(data / 'train'), str(out), storage],
                           check=True)
    sets = [('bare MCAP files (180 × .mcap)', data / 'train'),
            ('rosbag2 sqlite3 (180 folders, .db3)', data / 'train_sqlite3'),
            ('rosbag2 MCAP (180 folders)', data / 'train_mcap')]
    print(f'load average before: {load()}' + (' (runs under chrt -f 50)' if RT else ''))
    print('| input | 1 thread: wall (CPU) | 2 threads: wall (CPU) |')
    print('|---|---|---|')
    for label, d in sets:
        row = []
        for threads in [1, 2]:
            cmd = [binary, '--threads', str(threads), 'eval', str(d)]
            timed(cmd)  # warm the page cache
            runs = [timed(cmd) for _ in range(REPEATS)]
            wall = statistics.median(r[0] for r in runs)
            cpu = statistics.median(r[1] for r in runs)
            row.append(f'{wall:.3f} s ({cpu:.3f} s)')
        print(f'| {label} | {row[0]} | {row[1]} |')
    # The yardstick (issue 44): the same bare MCAP files read with Python rosbags (benches/rosbags_read.py),
    # against `omnical eval` on 2 threads.
    cmd = [sys.executable, str(here / 'rosbags_read.py'), str(data / 'train')]
    timed(cmd)
    rosbags = statistics.median(timed(cmd)[0] for _ in range(3))
    cmd = [binary, '--threads', '2', 'eval', str(data / 'train')]
    ours = statistics.median(timed(cmd)[0] for _ in range(REPEATS))
    print(f'rosbags (AnyReader, every message deserialized): {rosbags:.3f} s; omnical eval, 2 threads: {ours:.3f} s: '
          f'{rosbags / ours:.1f}x')
    print(f'load average after: {load()}')


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
