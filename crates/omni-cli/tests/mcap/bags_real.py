"""make_bags.py's bags as real systems record them: ros2_control's position-only wheels and unstamped
joint states, a motion-capture bridge on its own clock, and the same messages as ROS 1 bags (bz2, lz4,
encoder counts)."""

import math

import numpy as np
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.typesys import Stores, get_typestore

from bag_kit import (JOINT_STATE, MS, POSE_STAMPED, T, T0, TWIST, WHEELS, Bag, header, integrate_positions,
                     pose_stamped, rel, stamps, truth_pose, wheel_speeds, write_joints)

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
