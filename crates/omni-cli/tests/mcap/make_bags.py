#!/usr/bin/env python3
"""Test fixtures for omni-cli's MCAP reader and writer, made with a real ROS 2 bag client.

    make_bags.py OUT_DIR           write every bag as OUT_DIR/<name>.mcap, and OUT_DIR/expected.json
    make_bags.py --tiny OUT_DIR    write only the tiny bag (committed as tests/data/tiny_rosbags.mcap)
    make_bags.py --check FILE      read FILE (e.g. one written by omnical) with rosbags and mcap; print JSON

The bags are written with `rosbags` (pure Python, rosbag2's MCAP layout: profile `ros2`, schemas `ros2msg`,
messages `cdr`). rosbags writes `<dir>/<dir>.mcap` plus `metadata.yaml`; the inner file is self-contained, so
it is moved out to a bare `<name>.mcap`, which is how `omnical train data/*.mcap` sees recorded bags.

expected.json holds, per bag, the values the reader must return: times are seconds since ORIGIN_S (the whole
second of the first JointState stamp, computed as `(sec - ORIGIN_S) + nanosec * 1e-9` exactly as the reader
does), wheel speeds in the order wheel_a, wheel_b, wheel_c (rad/s), poses as [t_s, x_m, y_m, theta_rad] with
the heading unwrapped.

Needs: pip install rosbags mcap numpy (and, for --check to also decode through the schema text as Foxglove
does, mcap-ros2-support)
"""

import json
import math
import shutil
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types
JOINT_STATE = 'sensor_msgs/msg/JointState'
POSE_STAMPED = 'geometry_msgs/msg/PoseStamped'
POSE_COV_STAMPED = 'geometry_msgs/msg/PoseWithCovarianceStamped'
ODOMETRY = 'nav_msgs/msg/Odometry'
TF_MESSAGE = 'tf2_msgs/msg/TFMessage'
TWIST = 'geometry_msgs/msg/Twist'
TWIST_STAMPED = 'geometry_msgs/msg/TwistStamped'
STRING = 'std_msgs/msg/String'

ORIGIN_S = 1_700_000_000
T0 = ORIGIN_S * 10**9 + 250_000_000  # first JointState stamp, ns
MS = 1_000_000
WHEELS = ['wheel_a', 'wheel_b', 'wheel_c']
WHEEL_START = [0.1, 0.2, 0.3]


def rel(ns):
    """Seconds since ORIGIN_S, computed like the reader does."""
    return float(ns // 10**9 - ORIGIN_S) + float(ns % 10**9) * 1e-9


def header(ns, frame):
    return T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9),
                                    frame_id=frame)


def pose(x, y, yaw):
    return T['geometry_msgs/msg/Pose'](
        position=T['geometry_msgs/msg/Point'](x=x, y=y, z=0.0),
        orientation=T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)))


def vector3(x, y, z):
    return T['geometry_msgs/msg/Vector3'](x=x, y=y, z=z)


def twist(vx, vy, wz):
    return T[TWIST](linear=vector3(vx, vy, 0.0), angular=vector3(0.0, 0.0, wz))


def pose_stamped(ns, frame, x, y, yaw):
    return T[POSE_STAMPED](header=header(ns, frame), pose=pose(x, y, yaw))


def odometry(ns, frame, child, x, y, yaw):
    return T[ODOMETRY](
        header=header(ns, frame), child_frame_id=child,
        pose=T['geometry_msgs/msg/PoseWithCovariance'](pose=pose(x, y, yaw), covariance=np.zeros(36)),
        twist=T['geometry_msgs/msg/TwistWithCovariance'](twist=twist(0.1, 0.0, 0.2), covariance=np.zeros(36)))


def transform(ns, parent, child, x, y, yaw):
    q = pose(x, y, yaw).orientation
    return T['geometry_msgs/msg/TransformStamped'](
        header=header(ns, parent), child_frame_id=child,
        transform=T['geometry_msgs/msg/Transform'](translation=vector3(x, y, 0.0), rotation=q))


class Bag:
    """A rosbags MCAP writer that leaves a bare OUT/<name>.mcap behind."""

    def __init__(self, out, name, zstd=False):
        self.out, self.name = out, name
        self.dir = out / name
        shutil.rmtree(self.dir, ignore_errors=True)
        self.w = Writer(self.dir, version=9, storage_plugin=StoragePlugin.MCAP)
        if zstd:
            self.w.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self.w.open()
        self.conns = {}

    def topic(self, topic, msgtype, fmt='cdr'):
        self.conns[topic] = (self.w.add_connection(topic, msgtype, typestore=TS, serialization_format=fmt), msgtype)

    def write(self, topic, log_ns, msg):
        conn, msgtype = self.conns[topic]
        self.w.write(conn, log_ns, TS.serialize_cdr(msg, msgtype))

    def write_raw(self, topic, log_ns, data):
        self.w.write(self.conns[topic][0], log_ns, data)

    def close(self):
        self.w.close()
        path = self.out / f'{self.name}.mcap'
        shutil.move(self.dir / f'{self.name}.mcap', path)
        shutil.rmtree(self.dir)
        return path.name


def wheel_speeds(t):
    """Some smooth, distinct wheel speeds (rad/s) at t seconds after the first sample."""
    return [2.0 + math.sin(1.3 * t), -1.0 + 0.5 * math.cos(0.7 * t), 0.5 * t - 1.0]


def truth_pose(t):
    """The ground-truth pose at t seconds after the first sample; the heading crosses ±π near t = 2.82 s."""
    return 0.3 * t, 0.1 * math.sin(t), -2.5 + 2.0 * t


def stamps(start_ns, step_ns, n):
    return [start_ns + k * step_ns for k in range(n)]


def integrate_positions(ts_ns, vel):
    """Wheel angles: p_0 = WHEEL_START, p_k = p_(k-1) + v_k (t_k - t_(k-1)) (sample k covers (t_(k-1), t_k])."""
    pos = [list(WHEEL_START)]
    for k in range(1, len(ts_ns)):
        dt = (ts_ns[k] - ts_ns[k - 1]) * 1e-9
        pos.append([p + v * dt for p, v in zip(pos[-1], vel[k])])
    return pos


def write_joints(bag, ts_ns, vel, pos, topic='/joint_states', order=('arm_joint', 'wheel_c', 'wheel_a', 'wheel_b'),
                 with_velocity=True, latency_ns=MS + MS // 2):
    """JointState messages with the wheels in a shuffled order among other joints (mapped by name)."""
    for k, ns in enumerate(ts_ns):
        v = dict(zip(WHEELS, vel[k]), arm_joint=0.0)
        p = dict(zip(WHEELS, pos[k]), arm_joint=0.7)
        msg = T[JOINT_STATE](header=header(ns, ''), name=list(order),
                             position=np.array([p[j] for j in order]),
                             velocity=np.array([v[j] for j in order]) if with_velocity else np.zeros(0),
                             effort=np.zeros(0))
        bag.write(topic, ns + latency_ns, msg)


def rows(ts_ns, poses):
    return [[rel(ns), x, y, th] for ns, (x, y, th) in zip(ts_ns, poses)]


def inside(ts_ns, lo, hi):
    return [ns for ns in ts_ns if lo <= ns <= hi]


def normal_bag(out, name, zstd=False):
    """3 s of joints at 100 Hz, PoseStamped truth at 20 Hz starting before and ending after the wheel data,
    wheel odometry on /odom, Twist on /cmd_vel, and an arm's JointState topic the reader must not pick."""
    bag = Bag(out, name, zstd)
    for topic, msgtype in [('/joint_states', JOINT_STATE), ('/arm/joint_states', JOINT_STATE),
                           ('/mocap/pose', POSE_STAMPED), ('/odom', ODOMETRY), ('/cmd_vel', TWIST)]:
        bag.topic(topic, msgtype)
    js = stamps(T0, 10 * MS, 301)
    vel = [wheel_speeds(rel(ns) - rel(T0)) for ns in js]
    pos = integrate_positions(js, vel)
    bag.write('/cmd_vel', T0 - 500 * MS, twist(0.0, 0.0, 0.0))
    bag.write('/cmd_vel', T0 + 50 * MS, twist(0.3, 0.1, 2.0))
    write_joints(bag, js, vel, pos)
    for k, ns in enumerate(stamps(T0, 100 * MS, 31)):
        arm = T[JOINT_STATE](header=header(ns, ''), name=['shoulder', 'elbow'], position=np.array([0.1, 0.2]),
                             velocity=np.zeros(2), effort=np.zeros(0))
        bag.write('/arm/joint_states', ns, arm)
    gt = stamps(T0 - 100 * MS, 50 * MS, 65)  # 2 before the wheel data, 3 after
    gt_poses = [truth_pose(rel(ns) - rel(T0)) for ns in gt]
    for ns, (x, y, th) in zip(gt, gt_poses):
        bag.write('/mocap/pose', ns + 3 * MS, pose_stamped(ns, 'map', x, y, math.atan2(math.sin(th), math.cos(th))))
    od = stamps(T0, 20 * MS, 151)
    od_poses = [(1.02 * x, 1.02 * y, th) for x, y, th in (truth_pose(rel(ns) - rel(T0)) for ns in od)]
    for ns, (x, y, th) in zip(od, od_poses):
        bag.write('/odom', ns, odometry(ns, 'odom', 'base_link', x, y, math.atan2(math.sin(th), math.cos(th))))
    bag.write('/cmd_vel', T0 + 3000 * MS, twist(0.0, 0.0, 0.0))
    kept = [(ns, p) for ns, p in zip(gt, gt_poses) if js[0] <= ns <= js[-1]]
    return {
        'file': bag.close(),
        'wheel_t_s': [rel(ns) for ns in js],
        'wheel_rad_s': [v for row in vel for v in row],
        'wheel_start_rad': WHEEL_START,
        'truth': rows([ns for ns, _ in kept], [p for _, p in kept]),
        'truth_dropped': len(gt) - len(kept),
        'command': [math.hypot(0.3, 0.1), math.atan2(0.1, 0.3), 2.0],
        'recorded_odometry': rows(od, od_poses),
    }


def split_bag(out, name, gap=False):
    """Two motions separated by a 2 s standstill (wheels exactly 0, truth constant); TwistStamped commands.
    With gap=True the motion capture loses the robot from 2.4 s on, except for one last pose, so the second
    run has one ground-truth pose only."""
    bag = Bag(out, name)
    for topic, msgtype in [('/joint_states', JOINT_STATE), ('/mocap/pose', POSE_STAMPED),
                           ('/cmd_vel', TWIST_STAMPED)]:
        bag.topic(topic, msgtype)
    still = (150, 350)  # sample indices of the standstill (inclusive)
    js = stamps(T0, 10 * MS, 501)
    vel = [[0.0, 0.0, 0.0] if still[0] <= k <= still[1] else [3.0 + math.sin(k / 50), -2.0, 1.0] for k in range(501)]
    pos = integrate_positions(js, vel)
    write_joints(bag, js, vel, pos, order=WHEELS, latency_ns=0)

    def truth(t):
        if t < 1.5:
            return 0.2 * t, 0.0, 0.5 * t
        if t <= 3.5:
            return 0.3, 0.0, 0.75
        return 0.3, 0.2 * (t - 3.5), 0.75 - 0.5 * (t - 3.5)

    gt = stamps(T0, 50 * MS, 101)
    if gap:
        gt = [ns for ns in gt if rel(ns) - rel(T0) < 2.4 - 1e-9] + [gt[-1]]
    gt_poses = [truth(rel(ns) - rel(T0)) for ns in gt]
    for ns, (x, y, th) in zip(gt, gt_poses):
        bag.write('/mocap/pose', ns, pose_stamped(ns, 'map', x, y, th))
    for t_ms, (vx, vy, wz) in [(0, (0.2, 0.0, 0.5)), (1500, (0.0, 0.0, 0.0)), (3500, (0.0, 0.2, -0.5)),
                               (5000, (0.0, 0.0, 0.0))]:
        ns = T0 + t_ms * MS
        bag.write('/cmd_vel', ns, T[TWIST_STAMPED](header=header(ns, 'base_link'), twist=twist(vx, vy, wz)))
    cut = (still[0] + still[1]) // 2  # the reader cuts in the middle of the standstill
    runs = []
    for lo, hi, command in [(0, cut, [0.2, 0.0, 0.5]), (cut, 500, [0.2, math.pi / 2, -0.5])]:
        kept = [(ns, p) for ns, p in zip(gt, gt_poses) if js[lo] <= ns <= js[hi]]
        runs.append({
            'wheel_t_s': [rel(ns) for ns in js[lo:hi + 1]],
            'wheel_rad_s': [v for row in vel[lo:hi + 1] for v in row],
            'wheel_start_rad': pos[lo],
            'truth': rows([ns for ns, _ in kept], [p for _, p in kept]),
            'command': command,
        })
    return {'file': bag.close(), 'standstill_s': [rel(js[still[0]]), rel(js[still[1]])], 'runs': runs}


def position_only_bag(out, name):
    """JointState with positions only (velocity empty): the reader differentiates positions."""
    bag = Bag(out, name)
    bag.topic('/joint_states', JOINT_STATE)
    bag.topic('/mocap/pose', POSE_STAMPED)
    js = stamps(T0, 10 * MS, 201)
    vel = [wheel_speeds(rel(ns) - rel(T0)) for ns in js]
    pos = integrate_positions(js, vel)
    write_joints(bag, js, vel, pos, with_velocity=False)
    gt = stamps(T0, 50 * MS, 41)
    for ns in gt:
        x, y, th = truth_pose(rel(ns) - rel(T0))
        bag.write('/mocap/pose', ns, pose_stamped(ns, 'map', x, y, th))
    # What the reader recovers: backward differences of the positions as stored (float64), the first sample
    # taking the second one's speed.
    diff = [[(b - a) / (rel(t1) - rel(t0)) for a, b in zip(pos[k - 1], pos[k])]
            for k, (t0, t1) in enumerate(zip(js, js[1:]), start=1)]
    diff = [diff[0]] + diff
    return {'file': bag.close(), 'wheel_t_s': [rel(ns) for ns in js], 'wheel_rad_s_true': [v for r in vel for v in r],
            'wheel_rad_s': [v for r in diff for v in r], 'wheel_start_rad': WHEEL_START}


def simple_bag(out, name, truth_topic='/mocap/pose', truth_type=POSE_STAMPED, truth_frame='map', zstd=False,
               mutate=None, extra=()):
    """1 s of joints at 100 Hz and truth at 20 Hz; `mutate(kind, k, msg)` may change message k of each kind
    ('joints' or 'truth') and returns the message (or None to drop it)."""
    bag = Bag(out, name, zstd)
    bag.topic('/joint_states', JOINT_STATE)
    if truth_topic:
        bag.topic(truth_topic, truth_type)
    for topic, msgtype in extra:
        bag.topic(topic, msgtype)
    js = stamps(T0, 10 * MS, 101)
    vel = [wheel_speeds(rel(ns) - rel(T0)) for ns in js]
    pos = integrate_positions(js, vel)
    mutate = mutate or (lambda kind, k, msg: msg)
    for k, ns in enumerate(js):
        msg = T[JOINT_STATE](header=header(ns, ''), name=list(WHEELS), position=np.array(pos[k]),
                             velocity=np.array(vel[k]), effort=np.zeros(0))
        msg = mutate('joints', k, msg)
        if msg is not None:
            bag.write('/joint_states', ns, msg)
    gt = stamps(T0, 50 * MS, 21)
    poses = [truth_pose(rel(ns) - rel(T0)) for ns in gt]
    if truth_topic:
        for k, (ns, (x, y, th)) in enumerate(zip(gt, poses)):
            if truth_type == POSE_STAMPED:
                msg = pose_stamped(ns, truth_frame, x, y, th)
            elif truth_type == POSE_COV_STAMPED:
                msg = T[POSE_COV_STAMPED](header=header(ns, truth_frame), pose=T[
                    'geometry_msgs/msg/PoseWithCovariance'](pose=pose(x, y, th), covariance=np.eye(6).reshape(36)))
            else:
                msg = odometry(ns, truth_frame, 'base_link', x, y, th)
            msg = mutate('truth', k, msg)
            if msg is not None:
                bag.write(truth_topic, ns, msg)
    return bag, js, vel, pos, gt, poses


def simple_expected(bag, js, vel, gt, poses, **more):
    return dict(file=bag.close(), wheel_t_s=[rel(ns) for ns in js], wheel_rad_s=[v for r in vel for v in r],
                truth=rows(gt, poses), **more)


def tf_bag(out, name):
    """Ground truth as TF world -> robot_mocap on /tf, mixed with map -> odom and odom -> base_link."""
    bag, js, vel, pos, _, _ = simple_bag(out, name, truth_topic=None,
                                         extra=[('/tf', TF_MESSAGE), ('/tf_static', TF_MESSAGE)])
    tfm = T[TF_MESSAGE]
    bag.write('/tf_static', T0, tfm(transforms=[transform(T0, 'base_link', 'laser', 0.1, 0.0, 0.0)]))
    for ns in stamps(T0, 20 * MS, 51):
        x, y, th = truth_pose(rel(ns) - rel(T0))
        bag.write('/tf', ns, tfm(transforms=[transform(ns, 'map', 'odom', 0.0, 0.0, 0.0),
                                             transform(ns, 'odom', 'base_link', 0.9 * x, 0.9 * y, th)]))
    gt = stamps(T0 + 5 * MS, 50 * MS, 20)
    poses = [truth_pose(rel(ns) - rel(T0)) for ns in gt]
    for ns, (x, y, th) in zip(gt, poses):
        bag.write('/tf', ns, tfm(transforms=[transform(ns, '/world', 'robot_mocap', x, y, th)]))
    return simple_expected(bag, js, vel, gt, poses)


def tf_marker_bag(out, name):
    """Ground truth as TF world -> marker on /tf, a motion-capture marker mounted off the robot's centre:
    /tf_static holds marker -> mount -> base_link (10 cm back, 5 cm left, turned 30 degrees) and
    base_link -> laser. The expected poses are base_link's."""
    bag, js, vel, pos, _, _ = simple_bag(out, name, truth_topic=None,
                                         extra=[('/tf', TF_MESSAGE), ('/tf_static', TF_MESSAGE)])
    tfm = T[TF_MESSAGE]
    # marker -> mount (-0.1, 0, 0), mount -> base_link (0, 0.05, 30 deg): base_link in marker.
    statics = [('marker', 'mount', (-0.1, 0.0, 0.0)), ('mount', 'base_link', (0.0, 0.05, math.radians(30))),
               ('base_link', 'laser', (0.2, 0.0, 0.0))]
    bag.write('/tf_static', T0 - 100 * MS, tfm(transforms=[transform(T0 - 100 * MS, p, c, *o) for p, c, o in statics]))
    ox, oy, oth = -0.1, 0.05, math.radians(30)
    gt = stamps(T0 + 5 * MS, 50 * MS, 20)
    poses = [truth_pose(rel(ns) - rel(T0)) for ns in gt]
    for ns, (x, y, th) in zip(gt, poses):
        # marker = base_link composed with the inverse of (ox, oy, oth).
        mth = th - oth
        mx = x - (math.cos(mth) * ox - math.sin(mth) * oy)
        my = y - (math.sin(mth) * ox + math.cos(mth) * oy)
        bag.write('/tf', ns, tfm(transforms=[transform(ns, 'world', 'marker', mx, my, mth)]))
    return simple_expected(bag, js, vel, gt, poses)


def odom_truth_bag(out, name):
    """Ground truth as nav_msgs/Odometry in frame `world`, beside the wheel odometry on /odom (frame odom)."""
    bag, js, vel, pos, gt, poses = simple_bag(out, name, truth_topic='/ground_truth/odom', truth_type=ODOMETRY,
                                              truth_frame='world', extra=[('/odom', ODOMETRY)])
    od = stamps(T0, 50 * MS, 21)
    for ns in od:
        x, y, th = truth_pose(rel(ns) - rel(T0))
        bag.write('/odom', ns, odometry(ns, 'odom', 'base_link', 2 * x, 2 * y, th))
    return simple_expected(bag, js, vel, gt, poses)


def all_bags(out):
    expected = {
        'normal': normal_bag(out, 'normal'),
        'zstd': normal_bag(out, 'zstd', zstd=True),
        'split': split_bag(out, 'split'),
        'split_gap': split_bag(out, 'split_gap', gap=True),
        'position_only': position_only_bag(out, 'position_only'),
        'tf': tf_bag(out, 'tf'),
        'tf_marker': tf_marker_bag(out, 'tf_marker'),
        'odom_truth': odom_truth_bag(out, 'odom_truth'),
    }
    bag, js, vel, pos, gt, poses = simple_bag(out, 'pose_cov', truth_topic='/mocap/pose_cov',
                                              truth_type=POSE_COV_STAMPED, truth_frame='mocap')
    expected['pose_cov'] = simple_expected(bag, js, vel, gt, poses)

    # Bad inputs. Each is named after the error the reader must give.
    bag = simple_bag(out, 'no_truth', truth_topic=None, extra=[('/odom', ODOMETRY), ('/chatter', STRING)])[0]
    bag.write('/chatter', T0, T[STRING](data='hello'))
    bag.write('/odom', T0, odometry(T0, 'odom', 'base_link', 0.0, 0.0, 0.0))
    expected['no_truth'] = {'file': bag.close()}

    def drop_wheel_c(kind, k, msg):
        if kind == 'joints' and k == 5:
            msg.name, msg.position, msg.velocity = msg.name[:2], msg.position[:2], msg.velocity[:2]
        return msg

    def nan_velocity(kind, k, msg):
        # NaN with no position beside it (a NaN beside positions is ros2_control's way: see real_joint_states).
        if kind == 'joints' and k == 7:
            msg.velocity[1] = math.nan
            msg.position = np.zeros(0)
        return msg

    def nan_pose(kind, k, msg):
        if kind == 'truth' and k == 3:
            msg.pose.position.x = math.nan
        return msg

    def backwards(kind, k, msg):
        if kind == 'joints' and k == 10:
            msg.header.stamp.nanosec -= 25 * MS
        return msg

    def no_joints(kind, k, msg):
        return None if kind == 'joints' else msg

    for name, mutate in [('missing_joint', drop_wheel_c), ('nan_velocity', nan_velocity), ('nan_pose', nan_pose),
                         ('backwards', backwards), ('empty', no_joints)]:
        expected[name] = {'file': simple_bag(out, name, mutate=mutate)[0].close()}

    bag = simple_bag(out, 'ambiguous', extra=[('/vicon/pose', POSE_STAMPED)])[0]
    for k, ns in enumerate(stamps(T0, 50 * MS, 21)):
        bag.write('/vicon/pose', ns, pose_stamped(ns, 'map', 0.0, 0.0, 0.0))
    expected['ambiguous'] = {'file': bag.close()}

    bag = Bag(out, 'json_encoding')
    bag.topic('/joint_states', JOINT_STATE, fmt='json')
    bag.topic('/mocap/pose', POSE_STAMPED)
    for k, ns in enumerate(stamps(T0, 10 * MS, 11)):
        bag.write_raw('/joint_states', ns, json.dumps({'name': WHEELS, 'velocity': [1.0, 1.0, 1.0]}).encode())
        bag.write('/mocap/pose', ns, pose_stamped(ns, 'map', 0.0, 0.0, 0.0))
    expected['json_encoding'] = {'file': bag.close()}

    expected.update(real_joint_states(out))
    expected['mocap_clock'] = mocap_clock_bag(out, 'mocap_clock', 800 * MS)
    expected['mocap_lag'] = mocap_clock_bag(out, 'mocap_lag', 60 * MS)
    expected.update(ros1_bags(out))

    (out / 'not_mcap.mcap').write_text('this is a CSV file, not a bag\nt,x\n0,1\n')
    expected['not_mcap'] = {'file': 'not_mcap.mcap'}
    return expected


def real_joint_states(out):
    """/joint_states as real systems publish them. `ros2_control`: position-only wheels (velocity NaN), angles
    wrapped into [-pi, pi], an arm's joint_state_broadcaster on the same topic, and every 10th wheel message
    recorded twice. `unstamped`: header.stamp never filled (0); the log time is the sample time."""
    def wrap(a):
        return (a + math.pi) % (2 * math.pi) - math.pi

    expected = {}
    for name in ['ros2_control', 'unstamped']:
        bag = Bag(out, name)
        bag.topic('/joint_states', JOINT_STATE)
        bag.topic('/mocap/pose', POSE_STAMPED)
        js = stamps(T0, 10 * MS, 201)
        vel = [[4.0 * v for v in wheel_speeds(rel(ns) - rel(T0))] for ns in js]
        pos = integrate_positions(js, vel)
        for k, ns in enumerate(js):
            stamp = ns if name == 'ros2_control' else 0
            if name == 'ros2_control':
                msg = T[JOINT_STATE](header=header(stamp, ''), name=list(WHEELS),
                                     position=np.array([wrap(p) for p in pos[k]]),
                                     velocity=np.full(3, math.nan), effort=np.zeros(0))
            else:
                msg = T[JOINT_STATE](header=header(stamp, ''), name=list(WHEELS), position=np.array(pos[k]),
                                     velocity=np.array(vel[k]), effort=np.zeros(0))
            bag.write('/joint_states', ns, msg)
            if name == 'ros2_control' and k % 10 == 5:
                bag.write('/joint_states', ns, msg)
            if name == 'ros2_control' and k % 4 == 0:
                arm = T[JOINT_STATE](header=header(ns + 3 * MS, ''), name=['shoulder', 'elbow'],
                                     position=np.array([0.5, -0.5]), velocity=np.zeros(2), effort=np.zeros(0))
                bag.write('/joint_states', ns + 3 * MS, arm)
        for ns in stamps(T0, 50 * MS, 41):
            x, y, th = truth_pose(rel(ns) - rel(T0))
            bag.write('/mocap/pose', ns, pose_stamped(ns, 'map', x, y, th))
        expected[name] = {'file': bag.close(), 'wheel_t_s': [rel(ns) for ns in js],
                          'wheel_rad_s_true': [v for r in vel for v in r]}
    return expected


def mocap_clock_bag(out, name, offset_ns):
    """6 s of a three-wheeled base whose mocap bridge stamps /mocap/pose with its own clock: truth time =
    wheel time - offset_ns. The poses follow the wheels (body twist linear in the wheel speeds), so the
    clocks can be aligned from the motion."""
    m = [[0.0, 0.0289, -0.0289], [-0.0333, 0.0167, 0.0167], [0.1667, 0.1667, 0.1667]]  # m, m, rad per wheel rad
    bag = Bag(out, name)
    bag.topic('/joint_states', JOINT_STATE)
    bag.topic('/mocap/pose', POSE_STAMPED)
    js = stamps(T0, 10 * MS, 601)
    # Chirps: no time shift of the profiles is a linear mix of them (sinusoids of one frequency would be).
    vel = [[3.0 * math.sin(1.7 * t) + 1.0, 2.0 * math.sin(0.6 * t * t), 2.5 * math.cos(2.3 * t + 0.3 * t * t)]
           for t in (rel(ns) - rel(T0) for ns in js)]
    pos = integrate_positions(js, vel)
    write_joints(bag, js, vel, pos)
    x = y = th = 0.0
    truth = [(js[0], x, y, th)]
    for k in range(1, len(js)):
        dt = (js[k] - js[k - 1]) * 1e-9
        vx, vy, w = ([sum(mi * v for mi, v in zip(row, vel[k])) for row in m])
        x += (vx * math.cos(th) - vy * math.sin(th)) * dt
        y += (vx * math.sin(th) + vy * math.cos(th)) * dt
        th += w * dt
        truth.append((js[k], x, y, th))
    for ns, x, y, th in truth[::4]:
        bag.write('/mocap/pose', ns, pose_stamped(ns - offset_ns, 'map', x, y, th))
    return {'file': bag.close(), 'offset_s': offset_ns * 1e-9,
            'truth': [[rel(ns), x, y, th] for ns, x, y, th in truth[::4]]}


def ros1_bags(out):
    """The mocap_clock bag's messages (joints, mocap on the same clock, a TF, a Twist) written once more as
    ROS 1 bags (Noetic serialization: Header with seq, no NUL after strings), with bz2 and lz4 chunks: read,
    they must give the MCAP's runs exactly."""
    ts1 = get_typestore(Stores.ROS1_NOETIC)
    with_mcap = Bag(out, 'ros1_pair')
    for topic, msgtype in [('/joint_states', JOINT_STATE), ('/mocap/pose', POSE_STAMPED), ('/cmd_vel', TWIST)]:
        with_mcap.topic(topic, msgtype)
    js = stamps(T0, 10 * MS, 301)
    vel = [[3.0 * math.sin(1.7 * t) + 1.0, 2.0 * math.sin(0.6 * t * t), 2.5 * math.cos(2.3 * t + 0.3 * t * t)]
           for t in (rel(ns) - rel(T0) for ns in js)]
    pos = integrate_positions(js, vel)
    msgs = []
    for k, ns in enumerate(js):
        msgs.append(('/joint_states', JOINT_STATE, ns, dict(
            header=(ns, ''), name=list(WHEELS), position=np.array(pos[k]), velocity=np.array(vel[k]),
            effort=np.zeros(0))))
    for k, ns in enumerate(js[::5]):
        x, y, th = truth_pose(rel(ns) - rel(T0))
        msgs.append(('/mocap/pose', POSE_STAMPED, ns, dict(header=(ns, 'map'), pose=(x, y, th))))
    msgs.append(('/cmd_vel', TWIST, T0, None))

    def build(types, ros1, topic, msgtype, ns, fields):
        if msgtype == TWIST:
            v3 = types['geometry_msgs/msg/Vector3']
            return types[TWIST](linear=v3(x=0.25, y=-0.25, z=0.0), angular=v3(x=0.0, y=0.0, z=0.5))
        t, frame = fields['header']
        stamp = types['builtin_interfaces/msg/Time'](sec=t // 10**9, nanosec=t % 10**9)
        hdr = types['std_msgs/msg/Header']
        h = hdr(seq=7, stamp=stamp, frame_id=frame) if ros1 else hdr(stamp=stamp, frame_id=frame)
        if msgtype == JOINT_STATE:
            return types[JOINT_STATE](header=h, **{k: v for k, v in fields.items() if k != 'header'})
        x, y, th = fields['pose']
        p = types['geometry_msgs/msg/Pose'](position=types['geometry_msgs/msg/Point'](x=x, y=y, z=0.0),
                                            orientation=types['geometry_msgs/msg/Quaternion'](
                                                x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)))
        return types[POSE_STAMPED](header=h, pose=p)

    for topic, msgtype, ns, fields in msgs:
        with_mcap.write(topic, ns, build(T, False, topic, msgtype, ns, fields))
    expected = {'ros1_pair': {'file': with_mcap.close()}}

    def encoder(msgs, with_rpm):
        """The joints as a driver outside ros2_control publishes them: positions in counts of a 1024-count
        motor encoder behind a 30:1 gear, velocities in motor rpm (or none)."""
        out = []
        for topic, msgtype, ns, fields in msgs:
            if msgtype == JOINT_STATE:
                fields = dict(fields, position=np.round(fields['position'] * 30 * 1024 / (2 * math.pi)),
                              velocity=fields['velocity'] * 30 * 60 / (2 * math.pi) if with_rpm else np.zeros(0))
            out.append((topic, msgtype, ns, fields))
        return out

    bz2, lz4 = Ros1Writer.CompressionFormat.BZ2, Ros1Writer.CompressionFormat.LZ4
    for name, fmt, written in [('ros1_bz2', bz2, msgs), ('ros1_lz4', lz4, msgs),
                               ('ros1_counts_rpm', lz4, encoder(msgs, True)),
                               ('ros1_counts', lz4, encoder(msgs, False))]:
        path = out / f'{name}.bag'
        w = Ros1Writer(path)
        w.set_compression(fmt)
        w.open()
        conns = {t: w.add_connection(t, m, typestore=ts1) for t, m in
                 [('/joint_states', JOINT_STATE), ('/mocap/pose', POSE_STAMPED), ('/cmd_vel', TWIST)]}
        for topic, msgtype, ns, fields in written:
            w.write(conns[topic], ns, ts1.serialize_ros1(build(ts1.types, True, topic, msgtype, ns, fields), msgtype))
        w.close()
        expected[name] = {'file': path.name}
    return expected


def tiny_bag(out):
    """The committed bag: 1 s of joints, PoseStamped truth, a Twist command; zstd chunks."""
    bag, js, vel, pos, gt, poses = simple_bag(out, 'tiny_rosbags', zstd=True, extra=[('/cmd_vel', TWIST)])
    bag.write('/cmd_vel', T0, twist(0.25, -0.25, 0.5))
    return simple_expected(bag, js, vel, gt, poses, command=[math.hypot(0.25, 0.25), -math.pi / 4, 0.5],
                           wheel_start_rad=WHEEL_START)


def check(path):
    """Read a bag (e.g. written by omnical) with rosbags' AnyReader and the mcap package; print what they see."""
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader

    report = {'topics': {}, 'schemas_match_rosbags': {}}
    with open(path, 'rb') as f:
        reader = make_reader(f)
        report['profile'] = reader.get_header().profile
        summary = reader.get_summary()
        for ch in summary.channels.values():
            sc = summary.schemas[ch.schema_id]
            report['topics'][ch.topic] = {'schema': sc.name, 'schema_encoding': sc.encoding,
                                          'message_encoding': ch.message_encoding,
                                          'count': summary.statistics.channel_message_counts[ch.id]}
            report['schemas_match_rosbags'][sc.name] = sc.data.decode() == TS.generate_msgdef(sc.name, ros_version=2)[0]
        report['chunk_compression'] = sorted({c.compression for c in summary.chunk_indexes})
    try:  # Foxglove's own decoder, which parses the schema text as Foxglove does (pip install mcap-ros2-support)
        from mcap_ros2.decoder import DecoderFactory
    except ImportError:
        pass
    else:
        with open(path, 'rb') as f:
            decoded = make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
            report['decoded_from_schema_text'] = sum(1 for _ in decoded)
    msgs = {}
    with AnyReader([Path(path)], default_typestore=TS) as reader:
        for conn, log_ns, raw in reader.messages():
            m = reader.deserialize(raw, conn.msgtype)
            if conn.msgtype == JOINT_STATE:
                row = [m.header.stamp.sec, m.header.stamp.nanosec, list(m.name), m.velocity.tolist(),
                       m.position.tolist()]
            elif conn.msgtype == POSE_STAMPED:
                p = m.pose
                row = [m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id, p.position.x, p.position.y,
                       p.orientation.z, p.orientation.w]
            elif conn.msgtype == ODOMETRY:
                p = m.pose.pose
                row = [m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id, m.child_frame_id,
                       p.position.x, p.position.y, p.orientation.z, p.orientation.w]
            elif conn.msgtype == TWIST:
                row = [log_ns, m.linear.x, m.linear.y, m.angular.z]
            elif conn.msgtype == TWIST_STAMPED:
                t = m.twist
                row = [m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id, log_ns, t.linear.x, t.linear.y,
                       t.angular.z]
            else:
                row = [log_ns]
            msgs.setdefault(conn.topic, []).append(row)
    report['messages'] = msgs
    print(json.dumps(report))


def main(argv):
    if len(argv) == 3 and argv[1] == '--check':
        check(argv[2])
        return 0
    if len(argv) == 3 and argv[1] == '--tiny':
        out = Path(argv[2])
        out.mkdir(parents=True, exist_ok=True)
        (out / 'tiny_rosbags.json').write_text(json.dumps(tiny_bag(out)) + '\n')
        return 0
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = Path(argv[1])
    out.mkdir(parents=True, exist_ok=True)
    (out / 'expected.json').write_text(json.dumps(all_bags(out), indent=1) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
