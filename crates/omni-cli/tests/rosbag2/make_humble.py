#!/usr/bin/env python3
"""A Humble differential-drive robot's recordings, written as its stack writes them (issue 27's acceptance).

    make_humble.py OUT_DIR     write the recordings below into OUT_DIR, and OUT_DIR/expected.json

Three sessions of a diff-drive robot (25 s each, different motions), each a rosbag2 folder in sqlite3
storage (Humble's default):

    bag/session_0N/         joint_state_broadcaster's /joint_states (50 Hz; the two wheels and a caster
                            swivel, positions and velocities), /robot_description (the URDF, design radii
                            0.050 m, separation 0.300 m), /tf_static (base_footprint -> base_link,
                            base_link -> laser), diff_drive_controller's /odom (25 Hz, from the design), a header-less /cmd_vel, and
                            the motion capture's /mocap/pose (PoseStamped, 120 Hz, frame `world`) stamped by
                            its own clock: wheel time = mocap time + 0.8 s
    file/session_0N/        the same without /mocap/pose; file/mocap/session_0N.tum holds it (TUM, same
                            clock as the topic)
    odom/session_0N/        bag/ without /joint_states: the controller's /odom is the only wheel record
    robot.urdf              the URDF as a file

The true robot's right wheel is 2 % larger than the design (0.051 m against 0.050 m); its left wheel and
separation are the design's. The ground truth is base_link's pose plus 0.3 mm / 1 mrad noise.

Needs: pip install rosbags numpy
"""

import json
import math
import shutil
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types

ORIGIN_S = 1_717_000_000
R_LEFT, R_RIGHT, SEPARATION = 0.050, 0.051, 0.300     # the true robot. m
DESIGN_R, DESIGN_B = 0.050, 0.300                      # the URDF's
MOCAP_OFFSET_S = 0.8                                   # wheel time = mocap time + offset
DURATION_S, FINE_DT = 25.0, 1e-4
JS_DT_NS, GT_DT_NS = 20_000_000, 8_333_333             # 50 Hz, 120 Hz
NOISE_M, NOISE_RAD = 0.0003, 0.001

URDF = f"""<?xml version="1.0"?>
<robot name="humble_rover">
  <link name="base_footprint"/>
  <link name="base_link"><visual><geometry><box size="0.4 0.35 0.1"/></geometry></visual></link>
  <joint name="base_joint" type="fixed"><parent link="base_footprint"/><child link="base_link"/>
    <origin xyz="0 0 {DESIGN_R}"/></joint>
  <link name="left_wheel"><collision><origin rpy="1.5707963267948966 0 0"/>
    <geometry><cylinder radius="{DESIGN_R}" length="0.03"/></geometry></collision></link>
  <link name="right_wheel"><collision><origin rpy="1.5707963267948966 0 0"/>
    <geometry><cylinder radius="{DESIGN_R}" length="0.03"/></geometry></collision></link>
  <joint name="left_wheel_joint" type="continuous"><parent link="base_link"/><child link="left_wheel"/>
    <origin xyz="0 {DESIGN_B / 2} 0" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="right_wheel_joint" type="continuous"><parent link="base_link"/><child link="right_wheel"/>
    <origin xyz="0 {-DESIGN_B / 2} 0" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="caster"><visual><geometry><sphere radius="0.02"/></geometry></visual></link>
  <joint name="caster_swivel_joint" type="continuous"><parent link="base_link"/><child link="caster"/>
    <origin xyz="-0.15 0 -0.03"/><axis xyz="0 0 1"/></joint>
  <link name="laser"/>
  <joint name="laser_joint" type="fixed"><parent link="base_link"/><child link="laser"/>
    <origin xyz="0.12 0 0.1"/></joint>
</robot>
"""


def stamp(ns):
    return T['builtin_interfaces/msg/Time'](sec=int(ns) // 10**9, nanosec=int(ns) % 10**9)


def header(ns, frame):
    return T['std_msgs/msg/Header'](stamp=stamp(ns), frame_id=frame)


def quat(yaw):
    return T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def pose(x, y, yaw):
    return T['geometry_msgs/msg/Pose'](position=T['geometry_msgs/msg/Point'](x=float(x), y=float(y), z=0.0),
                                       orientation=quat(yaw))


def transform(ns, parent, child, x, y, z):
    return T['geometry_msgs/msg/TransformStamped'](
        header=header(ns, parent), child_frame_id=child,
        transform=T['geometry_msgs/msg/Transform'](translation=T['geometry_msgs/msg/Vector3'](x=x, y=y, z=z),
                                                   rotation=quat(0.0)))


def motion(session, t):
    """Forward speed (m/s) and yaw rate (rad/s) of session 1..3 at times t (s), with gentle starts and stops."""
    env = np.clip(t / 1.0, 0, 1) * np.clip((DURATION_S - 0.5 - t) / 1.0, 0, 1)
    p = 0.6 + 0.25 * session
    v = (0.25 + 0.15 * np.sin(p * 0.5 * t)) * env
    w = (0.8 * np.sin(p * t + session) + 0.3 * np.sin(2.3 * t)) * env
    return v, w


def simulate(session):
    """Wheel angles (left, right) and world poses of base_link on the fine grid from -0.2 s."""
    t = np.arange(-0.2, DURATION_S + 0.2, FINE_DT)
    v, w = motion(session, t)
    left, right = (v - w * SEPARATION / 2) / R_LEFT, (v + w * SEPARATION / 2) / R_RIGHT

    def integrate(f):
        out = np.zeros_like(f)
        out[1:] = np.cumsum(0.5 * (f[1:] + f[:-1]) * FINE_DT)
        return out
    theta = 0.4 * session + integrate(w)
    x = 0.5 * session + integrate(v * np.cos(theta))
    y = -0.3 + integrate(v * np.sin(theta))
    return t, integrate(left), integrate(right), x, y, theta


def diff_drive_odometry(left, right, dt):
    """diff_drive_controller's odometry (x, y, yaw, v, w per wheel sample) from wheel angles (rad) through the
    design radius and separation: each update integrates the wheel increments along an exact arc."""
    x = y = th = 0.0
    out = [(0.0, 0.0, 0.0, 0.0, 0.0)]
    for k in range(1, len(left)):
        dl, dr = DESIGN_R * (left[k] - left[k - 1]), DESIGN_R * (right[k] - right[k - 1])
        ds, dth = (dl + dr) / 2, (dr - dl) / DESIGN_B
        if abs(dth) < 1e-6:
            x += ds * math.cos(th + dth / 2)
            y += ds * math.sin(th + dth / 2)
        else:
            r = ds / dth
            x += r * (math.sin(th + dth) - math.sin(th))
            y -= r * (math.cos(th + dth) - math.cos(th))
        th += dth
        out.append((x, y, th, ds / dt, dth / dt))
    return out


def write(path, msgs):
    shutil.rmtree(path, ignore_errors=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    with Writer(path, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        conns = {}
        for _, topic, msgtype, _ in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, msgtype, typestore=TS)
        for ns, topic, msgtype, msg in sorted(msgs, key=lambda m: m[0]):
            w.write(conns[topic], ns, TS.serialize_cdr(msg, msgtype))


def session_messages(session):
    """(log ns, topic, type, message) of one session, and its mocap poses as TUM rows on the mocap clock."""
    rng = np.random.default_rng(40 + session)
    t_fine, left, right, x, y, theta = simulate(session)
    t0 = (ORIGIN_S + 100 * session) * 10**9
    msgs = [(t0 - 10**8, '/robot_description', 'std_msgs/msg/String', T['std_msgs/msg/String'](data=URDF))]
    msgs.append((t0 - 10**8, '/tf_static', 'tf2_msgs/msg/TFMessage', T['tf2_msgs/msg/TFMessage'](transforms=[
        transform(t0, 'base_footprint', 'base_link', 0.0, 0.0, DESIGN_R),
        transform(t0, 'base_link', 'laser', 0.12, 0.0, 0.1)])))
    js_ns = t0 + JS_DT_NS * np.arange(int(DURATION_S * 1e9) // JS_DT_NS + 1)
    tj = (js_ns - t0) * 1e-9
    pos = [np.interp(tj, t_fine, a) for a in (left, right)]
    prev = [np.interp(tj - JS_DT_NS * 1e-9, t_fine, a) for a in (left, right)]
    odom = diff_drive_odometry(pos[0], pos[1], JS_DT_NS * 1e-9)
    for k, ns in enumerate(js_ns):
        vel = [(p[k] - q[k]) / (JS_DT_NS * 1e-9) for p, q in zip(pos, prev)]
        m = T['sensor_msgs/msg/JointState'](
            header=header(ns, ''), name=['caster_swivel_joint', 'left_wheel_joint', 'right_wheel_joint'],
            position=np.array([0.1 * math.sin(tj[k]), pos[0][k], pos[1][k]]),
            velocity=np.array([0.0, vel[0], vel[1]]), effort=np.zeros(0))
        msgs.append((int(ns) + 400_000, '/joint_states', 'sensor_msgs/msg/JointState', m))
        if k % 2 == 0:
            # diff_drive_controller's odometry from the design radii (never ground truth), published at
            # 25 Hz from its 50 Hz updates.
            ox, oy, oth, ov, ow = odom[k]
            od = T['nav_msgs/msg/Odometry'](
                header=header(ns, 'odom'), child_frame_id='base_link',
                pose=T['geometry_msgs/msg/PoseWithCovariance'](pose=pose(ox, oy, oth), covariance=np.zeros(36)),
                twist=T['geometry_msgs/msg/TwistWithCovariance'](
                    twist=T['geometry_msgs/msg/Twist'](linear=T['geometry_msgs/msg/Vector3'](x=ov, y=0.0, z=0.0),
                                                       angular=T['geometry_msgs/msg/Vector3'](x=0.0, y=0.0, z=ow)),
                    covariance=np.zeros(36)))
            msgs.append((int(ns) + 600_000, '/odom', 'nav_msgs/msg/Odometry', od))
    v3 = T['geometry_msgs/msg/Vector3']
    msgs.append((t0, '/cmd_vel', 'geometry_msgs/msg/Twist',
                 T['geometry_msgs/msg/Twist'](linear=v3(x=0.3, y=0.0, z=0.0), angular=v3(x=0.0, y=0.0, z=0.5))))
    gt_ns = t0 + GT_DT_NS * np.arange(int(DURATION_S * 1e9) // GT_DT_NS)
    tg = (gt_ns - t0) * 1e-9
    gx = np.interp(tg, t_fine, x) + rng.normal(0, NOISE_M, len(tg))
    gy = np.interp(tg, t_fine, y) + rng.normal(0, NOISE_M, len(tg))
    gth = np.interp(tg, t_fine, theta) + rng.normal(0, NOISE_RAD, len(tg))
    offset_ns = int(MOCAP_OFFSET_S * 1e9)
    mocap, tum = [], []
    for ns, px, py, th in zip(gt_ns, gx, gy, gth):
        mocap_ns = int(ns) - offset_ns
        m = T['geometry_msgs/msg/PoseStamped'](header=header(mocap_ns, 'world'), pose=pose(px, py, th))
        # The bridge's messages reach the recorder 2 ms after the pose; the log time is the recorder's.
        mocap.append((int(ns) + 2_000_000, '/mocap/pose', 'geometry_msgs/msg/PoseStamped', m))
        q = quat(th)
        tum.append(f'{mocap_ns // 10**9}.{mocap_ns % 10**9:09d} {float(px)!r} {float(py)!r} 0.0 0.0 0.0 {float(q.z)!r} {float(q.w)!r}')
    return msgs, mocap, tum


def main(out):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / 'robot.urdf').write_text(URDF)
    (out / 'file' / 'mocap').mkdir(parents=True, exist_ok=True)
    for s in (1, 2, 3):
        msgs, mocap, tum = session_messages(s)
        write(out / 'bag' / f'session_0{s}', msgs + mocap)
        write(out / 'file' / f'session_0{s}', msgs)
        write(out / 'odom' / f'session_0{s}', [m for m in msgs if m[1] != '/joint_states'] + mocap)
        (out / 'file' / 'mocap' / f'session_0{s}.tum').write_text('\n'.join(tum) + '\n')
    expected = {'r_left_m': R_LEFT, 'r_right_m': R_RIGHT, 'separation_m': SEPARATION,
                'mocap_offset_s': MOCAP_OFFSET_S}
    (out / 'expected.json').write_text(json.dumps(expected, indent=1))


if __name__ == '__main__':
    main(sys.argv[1])
