import math, shutil, sys
from pathlib import Path
import numpy as np
from rosbags.rosbag1 import Writer as W1
from rosbags.rosbag2 import Writer as W2, StoragePlugin
from rosbags.typesys import Stores, get_typestore
T1 = get_typestore(Stores.ROS1_NOETIC); T2 = get_typestore(Stores.ROS2_HUMBLE)
out = Path(sys.argv[1])
T0 = 1_700_000_000 * 10**9 + 250_000_000
def msgs(T, ros1):
    Time = T.types['builtin_interfaces/msg/Time']
    def header(ns, frame, seq=0):
        st = Time(sec=ns // 10**9, nanosec=ns % 10**9)
        H = T.types['std_msgs/msg/Header']
        return H(seq=seq, stamp=st, frame_id=frame) if ros1 else H(stamp=st, frame_id=frame)
    JS = T.types['sensor_msgs/msg/JointState']; PS = T.types['geometry_msgs/msg/PoseStamped']
    P = T.types['geometry_msgs/msg/Pose']; Pt = T.types['geometry_msgs/msg/Point']; Q = T.types['geometry_msgs/msg/Quaternion']
    m = [[0.0, 0.0289, -0.0289], [-0.0333, 0.0167, 0.0167], [0.1667, 0.1667, 0.1667]]
    x = y = th = 0.0; js = []; gt = []
    for k in range(601):
        ns = T0 + k * 10**7; t = k * 0.01
        v = [3.0 * math.sin(1.7 * t) + 1.0, 2.0 * math.sin(0.6 * t * t), 2.5 * math.cos(2.3 * t + 0.3 * t * t)]
        if k:
            vx, vy, w = [sum(a * b for a, b in zip(r, v)) for r in m]
            x += (vx * math.cos(th) - vy * math.sin(th)) * 0.01; y += (vx * math.sin(th) + vy * math.cos(th)) * 0.01; th += w * 0.01
        js.append((ns, JS(header=header(ns, '', k), name=['wheel_a', 'wheel_b', 'wheel_c'], position=np.zeros(0), velocity=np.array(v), effort=np.zeros(0))))
        if k % 4 == 0:
            gt.append((ns, PS(header=header(ns, 'map', k), pose=P(position=Pt(x=x, y=y, z=0.0), orientation=Q(x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2))))))
    return js, gt
js, gt = msgs(T1, True)
p1 = out / 'rec.bag'
w = W1(p1)
if True:
    w.set_compression(W1.CompressionFormat.BZ2); w.open()
    cj = w.add_connection('/joint_states', 'sensor_msgs/msg/JointState', typestore=T1)
    cg = w.add_connection('/mocap/pose', 'geometry_msgs/msg/PoseStamped', typestore=T1)
    for ns, m in js: w.write(cj, ns, T1.serialize_ros1(m, 'sensor_msgs/msg/JointState'))
    for ns, m in gt: w.write(cg, ns, T1.serialize_ros1(m, 'geometry_msgs/msg/PoseStamped'))
w.close()
js, gt = msgs(T2, False)
d = out / 'rec2'
w = W2(d, version=9, storage_plugin=StoragePlugin.MCAP); w.open()
cj = w.add_connection('/joint_states', 'sensor_msgs/msg/JointState', typestore=T2)
cg = w.add_connection('/mocap/pose', 'geometry_msgs/msg/PoseStamped', typestore=T2)
for ns, m in js: w.write(cj, ns, T2.serialize_cdr(m, 'sensor_msgs/msg/JointState'))
for ns, m in gt: w.write(cg, ns, T2.serialize_cdr(m, 'geometry_msgs/msg/PoseStamped'))
w.close()
shutil.move(d / 'rec2.mcap', out / 'rec.mcap'); shutil.rmtree(d)
