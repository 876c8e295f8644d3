"""make_bags.py --check FILE: what rosbags and the mcap package (and, when installed, Foxglove's own decoder)
read in a bag, e.g. one omnical wrote, as JSON."""

import json
from pathlib import Path

from bag_kit import JOINT_STATE, ODOMETRY, POSE_STAMPED, TS, TWIST, TWIST_STAMPED

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
