#!/usr/bin/env python3
"""Test recordings for omni-cli's rosbag2 reader and ground-truth files, written with Python rosbags.

    make_recordings.py OUT_DIR     write everything below into OUT_DIR, and OUT_DIR/expected.json

One simulated recording of a three-wheel omni robot (30 s; three motion segments separated by 2 s
standstills; JointState at 100 Hz on /joint_states, motion capture PoseStamped at 125 Hz on /mocap/pose in
frame `map`), stored as:

    ref/rec.mcap                  bare MCAP (the inner file of a rosbags MCAP bag): the reference
    mcap/rec/                     rosbag2 folder, storage mcap
    db3/rec/                      rosbag2 folder, storage sqlite3
    split_mcap/rec/               two MCAP files rec_0.mcap, rec_1.mcap (cut at 15 s) and one metadata.yaml
    split_db3/rec/                the same with sqlite3
    db3_file_zstd/rec/            sqlite3, compression_mode FILE (rec.db3.zstd)
    db3_message_zstd/rec/         sqlite3, compression_mode MESSAGE
    mcap_message_zstd/rec/        mcap, compression_mode MESSAGE
    bare/rec.db3                  the sqlite3 file alone
    several/a/, several/b/        two recordings in one folder (b is the same motion, db3)
    nogt/rec/                     sqlite3 without the motion-capture topic (ground truth from a file)
    gt/...                        ground truth files (TUM, CSV) on other clocks, see expected.json
    urdf/rec/                     sqlite3 with the robot's URDF on /robot_description (std_msgs/msg/String);
    urdf/omni3.urdf               the same URDF as a file
    reversed_ids/rec.db3          the sqlite3 file with its message ids renumbered backwards (id order is not
                                  time order: read in (timestamp, id) order all the same)
    wal_clean/rec.db3             the sqlite3 file in WAL mode, closed cleanly (no log beside it)
    wal_pending/rec.db3           in WAL mode, its writer killed: the log (-wal) still holds a change (message
                                  5 of /joint_states cut to 40 bytes, as bad/truncated_blob.db3)
    bad/...                       broken inputs

Wheel speeds follow omnical's convention: sample k is the mean speed over (t_{k-1}, t_k] (the difference of
the wheel angle), so the ground truth and the wheels agree exactly up to the motion capture's noise.

Needs: pip install rosbags numpy
"""

import json
import math
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types
JOINT_STATE = 'sensor_msgs/msg/JointState'
POSE_STAMPED = 'geometry_msgs/msg/PoseStamped'

ORIGIN_S = 1_700_000_000
T0_NS = ORIGIN_S * 10**9 + 250_000_000   # first JointState stamp
WHEEL_DT_NS = 10_000_000                 # 100 Hz
N_WHEEL = 3001                           # 30 s
GT_DT_NS = 8_000_000                     # 125 Hz motion capture
GT_PHASE_NS = 3_000_000                  # its first stamp 3 ms after the first wheel stamp
FINE_DT = 1e-4                           # integration step. s
WHEELS = ['wheel_a', 'wheel_b', 'wheel_c']
RADIUS_M, DISTANCE_M = 0.05, 0.2
WHEEL_ANGLES = np.radians([90.0, 210.0, 330.0])
MOTION = [(0.5, 9.0), (11.0, 20.0), (22.0, 29.5)]   # s since the first wheel stamp
SPLIT_AT_S = 15.0
GT_NOISE_M, GT_NOISE_RAD = 0.0003, 0.001
# Ground truth clocks: wheel time = ground-truth time + offset.
OFFSETS_S = {'3s': 3.217, '50ms': 0.050}


def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def twist(t):
    """Body twist (vx m/s, vy m/s, wz rad/s) at times t (s since the first wheel stamp)."""
    env = np.zeros_like(t)
    for a, b in MOTION:
        env += smoothstep((t - a) / 0.5) * smoothstep((b - t) / 0.5)
    vx = 0.25 * np.sin(0.7 * t) * env
    vy = 0.18 * np.sin(1.1 * t + 1.0) * env
    wz = 0.9 * np.sin(0.45 * t + 0.3) * env + 0.3 * np.sin(2.1 * t) * env
    return vx, vy, wz


def simulate():
    """Wheel angles and world poses on the fine grid, from -0.1 s to 30.2 s."""
    t = np.arange(-0.1, 30.2, FINE_DT)
    vx, vy, wz = twist(t)
    # Wheel speed = (-sin(b) vx + cos(b) vy + L wz) / r for a wheel at angle b driving tangentially.
    rates = np.stack([(-math.sin(b) * vx + math.cos(b) * vy + DISTANCE_M * wz) / RADIUS_M for b in WHEEL_ANGLES])
    # Trapezoid integration.
    def integrate(f):
        out = np.zeros_like(f)
        out[..., 1:] = np.cumsum(0.5 * (f[..., 1:] + f[..., :-1]) * FINE_DT, axis=-1)
        return out
    angles = integrate(rates)
    theta = 0.3 + integrate(wz)
    c, s = np.cos(theta), np.sin(theta)
    x = 1.0 + integrate(c * vx - s * vy)
    y = -0.5 + integrate(s * vx + c * vy)
    return t, angles, x, y, theta


def interp(t_fine, f, t):
    return np.interp(t, t_fine, f)


def header(ns, frame):
    return T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9),
                                    frame_id=frame)


def pose_msg(ns, x, y, yaw):
    return T[POSE_STAMPED](header=header(ns, 'map'), pose=T['geometry_msgs/msg/Pose'](
        position=T['geometry_msgs/msg/Point'](x=float(x), y=float(y), z=0.0),
        orientation=T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))))


def messages():
    """All messages as (stamp ns, topic, CDR bytes), in time order, and the ground truth poses."""
    t_fine, angles, x, y, theta = simulate()
    rng = np.random.default_rng(17)
    out = []
    wheel_ns = T0_NS + WHEEL_DT_NS * np.arange(N_WHEEL)
    tw = (wheel_ns - T0_NS) * 1e-9
    prev = np.stack([interp(t_fine, a, tw - 0.01) for a in angles])
    now = np.stack([interp(t_fine, a, tw) for a in angles])
    vel = (now - prev) / 0.01
    for k, ns in enumerate(wheel_ns):
        m = T[JOINT_STATE](header=header(int(ns), 'base_link'), name=WHEELS, position=now[:, k].copy(),
                           velocity=vel[:, k].copy(), effort=np.zeros(0))
        out.append((int(ns), '/joint_states', TS.serialize_cdr(m, JOINT_STATE)))
    gt_ns = T0_NS + GT_PHASE_NS + GT_DT_NS * np.arange((N_WHEEL * WHEEL_DT_NS - GT_PHASE_NS) // GT_DT_NS)
    tg = (gt_ns - T0_NS) * 1e-9
    gx = interp(t_fine, x, tg) + rng.normal(0, GT_NOISE_M, len(tg))
    gy = interp(t_fine, y, tg) + rng.normal(0, GT_NOISE_M, len(tg))
    gyaw = interp(t_fine, theta, tg) + rng.normal(0, GT_NOISE_RAD, len(tg))
    truth = []
    for ns, px, py, yaw in zip(gt_ns, gx, gy, gyaw):
        out.append((int(ns), '/mocap/pose', TS.serialize_cdr(pose_msg(int(ns), px, py, yaw), POSE_STAMPED)))
        truth.append((int(ns), float(px), float(py), float(yaw)))
    out.sort(key=lambda m: m[0])
    return out, truth


TYPES = {'/joint_states': JOINT_STATE, '/mocap/pose': POSE_STAMPED, '/robot_description': 'std_msgs/msg/String'}


def write_bag(path, msgs, storage, compression=None):
    """A rosbags bag at `path` (a folder) holding `msgs`."""
    w = Writer(path, version=9, storage_plugin=storage)
    if compression is not None:
        w.set_compression(compression, CompressionFormat.ZSTD)   # before open
    with w:
        conns = {}
        for topic in sorted({m[1] for m in msgs}):
            conns[topic] = w.add_connection(topic, TYPES[topic], typestore=TS)
        for ns, topic, data in msgs:
            w.write(conns[topic], ns, data)


def write_split(path, msgs, storage, ext):
    """One recording in two storage files (rosbags writes no split bags: two bags, then one metadata.yaml)."""
    cut = T0_NS + int(SPLIT_AT_S * 1e9)
    parts = [[m for m in msgs if m[0] < cut], [m for m in msgs if m[0] >= cut]]
    tmp = path.parent / (path.name + '_parts')
    path.mkdir(parents=True)
    for i, part in enumerate(parts):
        write_bag(tmp / str(i), part, storage)
        shutil.move(tmp / str(i) / f'{i}.{ext}', path / f'rec_{i}.{ext}')
    meta = (tmp / '0' / 'metadata.yaml').read_text()
    lines = meta.splitlines()
    # Swap the relative file paths and the counts for those of the whole recording.
    out, skip = [], False
    for line in lines:
        if line.strip().startswith('relative_file_paths:'):
            out.append(line)
            indent = line[:len(line) - len(line.lstrip())]
            out += [f'{indent}- rec_0.{ext}', f'{indent}- rec_1.{ext}']
            skip = True
            continue
        if skip and line.lstrip().startswith('- '):
            continue
        skip = False
        out.append(line)
    text = '\n'.join(out) + '\n'
    for topic in TYPES:
        n0 = sum(1 for m in parts[0] if m[1] == topic)
        n = sum(1 for m in msgs if m[1] == topic)
        text = text.replace(f'message_count: {n0}\n    topic_metadata:\n      name: {topic}\n',
                            f'message_count: {n}\n    topic_metadata:\n      name: {topic}\n')
    (path / 'metadata.yaml').write_text(text)
    shutil.rmtree(tmp)


def quat(yaw):
    return 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)


def stamp_text(ns):
    return f'{ns // 10**9}.{ns % 10**9:09d}'


def omni3_urdf():
    """The simulated robot as a URDF: each wheel's joint frame yawed to its angle, turning about -x (the axle
    points inwards), so positive speed pushes along the counter-clockwise tangent, as in `twist`."""
    parts = []
    for name, a in zip(WHEELS, WHEEL_ANGLES):
        a = float(a)
        parts.append(
            f'<link name="{name}_link"><collision><origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/>\n'
            f'  <geometry><cylinder radius="{RADIUS_M!r}" length="0.03"/></geometry></collision></link>\n'
            f'<joint name="{name}" type="continuous"><parent link="base_link"/><child link="{name}_link"/>\n'
            f'  <origin xyz="{DISTANCE_M * math.cos(a)!r} {DISTANCE_M * math.sin(a)!r} 0.0" rpy="0 0 {a!r}"/>'
            f'<axis xyz="-1 0 0"/></joint>\n')
    return ('<?xml version="1.0"?>\n<robot name="omni3">\n<link name="base_link"/>\n' + ''.join(parts)
            + '</robot>\n')


def write_tum(path, truth, offset_ns):
    """TUM (evo): `t x y z qx qy qz qw`, t on the ground truth's clock = wheel clock - offset."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, 'w') as f:
        f.write('# timestamp tx ty tz qx qy qz qw (motion capture clock)\n')
        for ns, x, y, yaw in truth:
            q = quat(yaw)
            f.write(' '.join([stamp_text(ns - offset_ns)] + [repr(v) for v in (x, y, 0.0, *q)]) + '\n')


def write_csv(path, truth, offset_ns):
    """A motion-capture CSV: time in ns since the epoch, position in mm, heading in degrees."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, 'w') as f:
        f.write('frame,stamp_ns,pos_x_mm,pos_y_mm,pos_z_mm,heading_deg\n')
        for i, (ns, x, y, yaw) in enumerate(truth):
            f.write(f'{i},{ns - offset_ns},{x * 1000.0!r},{y * 1000.0!r},0.0,{math.degrees(yaw)!r}\n')


# A writer killed after a commit in WAL mode: the change stays in the log, not in the database file.
PENDING = """
import os, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.execute('PRAGMA journal_mode=WAL')
db.execute('PRAGMA wal_autocheckpoint=0')
tid = db.execute("SELECT id FROM topics WHERE name = '/joint_states'").fetchone()[0]
ids = [r[0] for r in db.execute('SELECT id FROM messages WHERE topic_id = ? ORDER BY timestamp, id', (tid,))]
db.execute('UPDATE messages SET data = substr(data, 1, 40) WHERE id = ?', (ids[5],))
db.commit()
os._exit(0)
"""


def main(out):
    out = Path(out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    msgs, truth = messages()

    write_bag(out / 'tmp_ref', msgs, StoragePlugin.MCAP)
    (out / 'ref').mkdir()
    shutil.move(out / 'tmp_ref' / 'tmp_ref.mcap', out / 'ref' / 'rec.mcap')
    shutil.rmtree(out / 'tmp_ref')

    # rosbags names the storage file after the folder: rec/rec.mcap, rec/rec.db3.
    write_bag(out / 'mcap' / 'rec', msgs, StoragePlugin.MCAP)
    write_bag(out / 'db3' / 'rec', msgs, StoragePlugin.SQLITE3)
    write_split(out / 'split_mcap' / 'rec', msgs, StoragePlugin.MCAP, 'mcap')
    write_split(out / 'split_db3' / 'rec', msgs, StoragePlugin.SQLITE3, 'db3')
    write_bag(out / 'db3_file_zstd' / 'rec', msgs, StoragePlugin.SQLITE3, CompressionMode.FILE)
    write_bag(out / 'db3_message_zstd' / 'rec', msgs, StoragePlugin.SQLITE3, CompressionMode.MESSAGE)
    write_bag(out / 'mcap_message_zstd' / 'rec', msgs, StoragePlugin.MCAP, CompressionMode.MESSAGE)
    (out / 'bare').mkdir()
    shutil.copy(out / 'db3' / 'rec' / 'rec.db3', out / 'bare' / 'rec.db3')
    write_bag(out / 'several' / 'a', msgs, StoragePlugin.MCAP)
    write_bag(out / 'several' / 'b', msgs, StoragePlugin.SQLITE3)
    write_bag(out / 'nogt' / 'rec', [m for m in msgs if m[1] == '/joint_states'], StoragePlugin.SQLITE3)
    urdf = omni3_urdf()
    (out / 'urdf').mkdir()
    (out / 'urdf' / 'omni3.urdf').write_text(urdf)
    description = (T0_NS - 1_000_000, '/robot_description',
                   TS.serialize_cdr(T['std_msgs/msg/String'](data=urdf), 'std_msgs/msg/String'))
    write_bag(out / 'urdf' / 'rec', [description] + msgs, StoragePlugin.SQLITE3)

    expected = {'origin_s': ORIGIN_S, 'offsets_s': OFFSETS_S, 'split_at_s': SPLIT_AT_S,
                'n_wheel': N_WHEEL, 'n_truth': len(truth),
                'motion_s': MOTION, 'wheel_joints': WHEELS}
    for name, off in OFFSETS_S.items():
        off_ns = round(off * 1e9)
        write_tum(out / 'gt' / f'tum_{name}' / 'rec.tum', truth, off_ns)
        write_csv(out / 'gt' / f'csv_{name}' / 'rec.csv', truth, off_ns)
    write_tum(out / 'gt' / 'same_clock.tum', truth, 0)

    for d in ['wal_clean', 'wal_pending', 'reversed_ids']:
        (out / d).mkdir()
        shutil.copy(out / 'db3' / 'rec' / 'rec.db3', out / d / 'rec.db3')
    db = sqlite3.connect(out / 'wal_clean' / 'rec.db3')
    db.execute('PRAGMA journal_mode=WAL')
    db.close()
    subprocess.run([sys.executable, '-c', PENDING, str(out / 'wal_pending' / 'rec.db3')], check=True)
    assert (out / 'wal_pending' / 'rec.db3-wal').stat().st_size > 0
    db = sqlite3.connect(out / 'reversed_ids' / 'rec.db3')
    top = db.execute('SELECT max(id) FROM messages').fetchone()[0]
    db.execute('UPDATE messages SET id = -id')
    db.execute('UPDATE messages SET id = ? + id', (top + 1,))
    db.commit()
    db.close()

    bad = out / 'bad'
    write_bag(bad / 'missing_file', msgs, StoragePlugin.SQLITE3)
    meta = bad / 'missing_file' / 'metadata.yaml'
    meta.write_text(meta.read_text().replace('- missing_file.db3', '- missing_file.db3\n  - missing_file_1.db3'))
    write_bag(bad / 'unknown_storage', msgs, StoragePlugin.SQLITE3)
    meta = bad / 'unknown_storage' / 'metadata.yaml'
    meta.write_text(meta.read_text().replace('storage_identifier: sqlite3', 'storage_identifier: hdf5'))
    (bad / 'empty.db3').write_bytes(b'')
    shutil.copy(out / 'db3' / 'rec' / 'rec.db3', bad / 'truncated_blob.db3')
    db = sqlite3.connect(bad / 'truncated_blob.db3')
    topic_id = db.execute("SELECT id FROM topics WHERE name = '/joint_states'").fetchone()[0]
    ids = [r[0] for r in db.execute('SELECT id FROM messages WHERE topic_id = ? ORDER BY timestamp, id', (topic_id,))]
    db.execute('UPDATE messages SET data = substr(data, 1, 40) WHERE id = ?', (ids[5],))
    db.commit()
    db.close()
    expected['truncated_blob_message'] = 5
    tum = (out / 'gt' / 'tum_50ms' / 'rec.tum').read_text().splitlines()
    nan = list(tum)
    nan[11] = ' '.join(nan[11].split()[:2] + ['nan'] + nan[11].split()[3:])
    (bad / 'nan.tum').write_text('\n'.join(nan) + '\n')
    dec = list(tum)
    dec[21], dec[22] = dec[22], dec[21]
    (bad / 'decreasing.tum').write_text('\n'.join(dec) + '\n')
    write_tum(bad / 'elsewhen.tum', truth, -3600 * 10**9)

    (out / 'expected.json').write_text(json.dumps(expected, indent=1))


if __name__ == '__main__':
    main(sys.argv[1])
