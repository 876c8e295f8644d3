"""make_bags.py's bags of one robot's motion, one per way of recording the ground truth (PoseStamped,
PoseWithCovarianceStamped, TF chains, Odometry), with standstills, position-only joints, and the tiny bag
committed as tests/data/tiny_rosbags.mcap. Each returns the values the reader must give (expected.json).
"""

import math

import numpy as np

from bag_kit import (JOINT_STATE, MS, ODOMETRY, POSE_COV_STAMPED, POSE_STAMPED, T, T0, TF_MESSAGE, TWIST,
                     TWIST_STAMPED, WHEEL_START, WHEELS, Bag, header, integrate_positions, odometry, pose,
                     pose_stamped, rel, rows, stamps, transform, truth_pose, twist, wheel_speeds, write_joints)

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


def tiny_bag(out):
    """The committed bag: 1 s of joints, PoseStamped truth, a Twist command; zstd chunks."""
    bag, js, vel, pos, gt, poses = simple_bag(out, 'tiny_rosbags', zstd=True, extra=[('/cmd_vel', TWIST)])
    bag.write('/cmd_vel', T0, twist(0.25, -0.25, 0.5))
    return simple_expected(bag, js, vel, gt, poses, command=[math.hypot(0.25, 0.25), -math.pi / 4, 0.5],
                           wheel_start_rad=WHEEL_START)
