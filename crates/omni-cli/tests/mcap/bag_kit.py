"""The tools make_bags.py's fixtures are written with: the ROS 2 message types (rosbags' Humble typestore),
message builders, a rosbags MCAP writer that leaves a bare <name>.mcap, and the wheel and ground-truth
motions the bags record. Times: ns since the epoch in the messages, seconds since ORIGIN_S in expected.json
(`rel`). Also imported by tests/data/bad/make_bad.py.
"""

import math
import shutil

import numpy as np
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
