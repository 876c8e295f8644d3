#!/usr/bin/env python3
"""The yardstick of benches/loading.py: what a Python user does to read the same recordings with rosbags
(`AnyReader`): every bag of DIR opened, every JointState and PoseStamped message deserialized, the wheel
speeds and poses gathered into numpy arrays per bag. Prints the number of bags and messages read.

    python3 benches/rosbags_read.py DIR
"""

import sys
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader


def read(bag):
    wheels, poses = [], []
    with AnyReader([bag]) as reader:
        for conn, stamp, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.msgtype == 'sensor_msgs/msg/JointState':
                wheels.append([stamp * 1e-9, *msg.velocity])
            elif conn.msgtype == 'geometry_msgs/msg/PoseStamped':
                p, q = msg.pose.position, msg.pose.orientation
                poses.append([stamp * 1e-9, p.x, p.y, q.z, q.w])
    return np.array(wheels), np.array(poses)


def main(folder):
    folder = Path(folder)
    bags = sorted(folder.glob('*.mcap')) or sorted(p for p in folder.iterdir() if (p / 'metadata.yaml').exists())
    messages = 0
    for bag in bags:
        w, p = read(bag)
        messages += len(w) + len(p)
    print(f'{len(bags)} bags, {messages} messages')


if __name__ == '__main__':
    main(sys.argv[1])
