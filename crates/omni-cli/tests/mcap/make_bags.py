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
import sys
from pathlib import Path

import numpy as np

from bag_kit import (JOINT_STATE, MS, ODOMETRY, POSE_COV_STAMPED, POSE_STAMPED, STRING, T, T0, WHEELS, Bag,
                     odometry, pose_stamped, stamps)
from bags_real import mocap_clock_bag, real_joint_states, ros1_bags
from bags_truth import (normal_bag, odom_truth_bag, position_only_bag, simple_bag, simple_expected, split_bag,
                        tf_bag, tf_marker_bag, tiny_bag)
from check_bag import check

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
