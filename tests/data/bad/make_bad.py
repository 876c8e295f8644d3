#!/usr/bin/env python3
"""The bad-input corpus: small files omnical must refuse with a clear message, never a panic.

    .venv/bin/python tests/data/bad/make_bad.py      (re)writes tests/data/bad/{mcap,csv}/*

Each file is paired with the words its error must contain in tests/data/bad/EXPECTED.toml; the test
crates/omni-cli/tests/bad_inputs.rs runs `omnical eval` (and `train`) on every file. The output is
deterministic, so re-running the script leaves git clean. Needs rosbags, mcap and numpy
(requirements-dev.txt): valid bags are written with rosbags (rosbag2's layout) or the mcap package, then
damaged byte by byte (truncated, lengths and bytes corrupted for each MCAP record kind) or written with
bad messages (CDR of the wrong length or type, NaN/Inf, bad stamps, too few samples, absurd values,
missing ground truth, joint names that do not match).
"""

import math
import struct
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2] / 'crates/omni-cli/tests/mcap'))

import numpy as np  # noqa: E402
from bag_kit import (JOINT_STATE, MS, POSE_STAMPED, T, T0, TS, WHEELS, Bag, header,  # noqa: E402
                     pose_stamped)
from mcap.writer import CompressionType, Writer as McapWriter  # noqa: E402

OPCODES = {0x01: 'header', 0x02: 'footer', 0x03: 'schema', 0x04: 'channel', 0x05: 'message', 0x06: 'chunk',
           0x07: 'message_index', 0x08: 'chunk_index', 0x09: 'attachment', 0x0A: 'attachment_index',
           0x0B: 'statistics', 0x0C: 'metadata', 0x0D: 'metadata_index', 0x0E: 'summary_offset',
           0x0F: 'data_end'}
MAGIC = b'\x89MCAP0\r\n'
N_JOINTS, N_TRUTH = 11, 3  # 0.1 s of wheel data at 100 Hz, truth at 20 Hz


def joint_state(k, ns, names=WHEELS, velocity=None):
    v = velocity if velocity is not None else [1.0 + 0.1 * k, -0.5, -0.5]
    return T[JOINT_STATE](header=header(ns, ''), name=list(names), position=np.array([0.01 * k] * len(names)),
                          velocity=np.array(v, dtype=float), effort=np.zeros(0))


def cdr(msg, msgtype=JOINT_STATE):
    return bytes(TS.serialize_cdr(msg, msgtype))


def joint_stamps():
    return [T0 + k * 10 * MS for k in range(N_JOINTS)]


def truth_stamps():
    return [T0 + k * 50 * MS for k in range(N_TRUTH)]


def small_bag(out, name, joints=None, truth=None, raw_joints=None):
    """A rosbags bag: /joint_states and /mocap/pose (PoseStamped, frame map). `joints(k, ns)` and
    `truth(k, ns)` return the message (None drops it); `raw_joints(k, ns)` returns CDR bytes instead."""
    bag = Bag(out, name)
    bag.topic('/joint_states', JOINT_STATE)
    bag.topic('/mocap/pose', POSE_STAMPED)
    for k, ns in enumerate(joint_stamps()):
        if raw_joints:
            data = raw_joints(k, ns)
            if data is not None:
                bag.write_raw('/joint_states', ns, data)
            continue
        msg = joints(k, ns) if joints else joint_state(k, ns)
        if msg is not None:
            bag.write('/joint_states', ns, msg)
    for k, ns in enumerate(truth_stamps()):
        msg = truth(k, ns) if truth else pose_stamped(ns, 'map', 0.01 * k, 0.0, 0.05 * k)
        if msg is not None:
            bag.write('/mocap/pose', ns, msg)
    bag.close()
    return out / f'{name}.mcap'


def mcap_bag(path, schema_encoding='ros2msg', message_encoding='cdr', schema_name=JOINT_STATE, chunked=True,
             joints=None):
    """A bag written with the mcap package (no rosbags): top-level Schema/Channel/Message records when not
    chunked, so each record kind can be damaged."""
    with open(path, 'wb') as f:
        w = McapWriter(f, use_chunking=chunked, compression=CompressionType.NONE)
        w.start(profile='ros2', library='omnical-bad-corpus')
        js = w.register_schema(schema_name, schema_encoding, TS.generate_msgdef(JOINT_STATE, ros_version=2)[0]
                               .encode())
        ps = w.register_schema(POSE_STAMPED, 'ros2msg', TS.generate_msgdef(POSE_STAMPED, ros_version=2)[0].encode())
        cj = w.register_channel('/joint_states', message_encoding, js)
        cp = w.register_channel('/mocap/pose', 'cdr', ps)
        for k, ns in enumerate(joint_stamps()):
            data = joints(k, ns) if joints else cdr(joint_state(k, ns))
            w.add_message(cj, log_time=ns, data=data, publish_time=ns, sequence=k)
        for k, ns in enumerate(truth_stamps()):
            w.add_message(cp, log_time=ns, data=cdr(pose_stamped(ns, 'map', 0.01 * k, 0.0, 0.05 * k),
                                                    POSE_STAMPED), publish_time=ns, sequence=k)
        w.finish()
    return path


def records(data):
    """(offset, opcode, body length) of each top-level record after the leading magic."""
    out, pos = [], len(MAGIC)
    while pos + 9 <= len(data):
        op, n = data[pos], struct.unpack_from('<Q', data, pos + 1)[0]
        out.append((pos, op, n))
        if op == 0x02:
            break
        pos += 9 + n
    return out


def first(data, opcode, skip=0):
    found = [r for r in records(data) if r[1] == opcode]
    return found[skip] if len(found) > skip else None


def damage(src, out_dir, prefix):
    """For each record kind in `src`: truncated inside its first record, its length field made huge, and a
    byte in the middle of its body flipped. Writes <prefix>_<kind>_{truncated,length,flipped}.mcap."""
    data = src.read_bytes()
    made = []
    seen = set()
    for pos, op, n in records(data):
        kind = OPCODES.get(op, f'op{op:02x}')
        if kind in seen:
            continue
        seen.add(kind)
        cut = data[:pos + 9 + n // 2] if n > 1 else data[:pos + 5]
        huge = bytearray(data)
        struct.pack_into('<Q', huge, pos + 1, 0x7FFF_FFFF_FFFF_FFF0)
        flip = bytearray(data)
        if n > 0:
            flip[pos + 9 + n // 2] ^= 0xFF
        for suffix, blob in [('truncated', cut), ('length', bytes(huge)), ('flipped', bytes(flip))]:
            if suffix == 'flipped' and n == 0:
                continue
            p = out_dir / f'{prefix}_{kind}_{suffix}.mcap'
            p.write_bytes(blob)
            made.append(p)
    return made


def mcap_corpus(out):
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob('*.mcap'):
        old.unlink()
    tmp = out / 'tmp'
    tmp.mkdir(exist_ok=True)

    # Damaged files, every record kind: a rosbags bag (chunked) and an mcap-package bag (records at top level).
    damage(small_bag(tmp, 'rosbags'), out, 'rosbags')
    damage(mcap_bag(tmp / 'flat.mcap', chunked=False), out, 'flat')
    (out / 'empty.mcap').write_bytes(b'')
    (out / 'magic_only.mcap').write_bytes(MAGIC)
    (out / 'not_mcap.mcap').write_bytes(b't_s,x_m\n0,1\n')

    # Wrong schemas and encodings.
    mcap_bag(out / 'schema_jsonschema.mcap', schema_encoding='jsonschema')
    mcap_bag(out / 'message_encoding_json.mcap', message_encoding='json')
    mcap_bag(out / 'schema_unknown_type.mcap', schema_name='my_msgs/msg/WheelSpeeds')
    pose = cdr(pose_stamped(T0, 'map', 0.0, 0.0, 0.0), POSE_STAMPED)
    mcap_bag(out / 'schema_wrong_type.mcap', joints=lambda k, ns: pose)

    # CDR of the wrong length.
    def cut(k, ns, n):
        data = cdr(joint_state(k, ns))
        return data[:n] if k == 4 else data

    small_bag(out, 'cdr_truncated', raw_joints=lambda k, ns: cut(k, ns, len(cdr(joint_state(k, ns))) - 8))
    small_bag(out, 'cdr_header_only', raw_joints=lambda k, ns: cut(k, ns, 4))
    small_bag(out, 'cdr_empty', raw_joints=lambda k, ns: cut(k, ns, 0))

    def huge_names(k, ns):
        data = bytearray(cdr(joint_state(k, ns)))
        if k == 2:  # header: 4 encapsulation + 8 stamp + 4+1(+pad to 4) frame_id "" → names count at 20
            struct.pack_into('<I', data, 20, 0x7FFF_FFFF)
        return bytes(data)

    small_bag(out, 'cdr_huge_array_length', raw_joints=huge_names)
    small_bag(out, 'cdr_bad_encapsulation',
              raw_joints=lambda k, ns: b'\x00\x07\x00\x00' + cdr(joint_state(k, ns))[4:])
    small_bag(out, 'velocity_two_entries',
              joints=lambda k, ns: joint_state(k, ns, velocity=[1.0, 2.0]) if k == 3 else joint_state(k, ns))

    # NaN / Inf.
    small_bag(out, 'inf_velocity', joints=lambda k, ns: joint_state(k, ns, velocity=[1.0, math.inf, 0.0])
              if k == 6 else joint_state(k, ns))
    small_bag(out, 'nan_truth', truth=lambda k, ns: pose_stamped(ns, 'map', 0.0, math.nan, 0.0) if k == 1
              else pose_stamped(ns, 'map', 0.0, 0.0, 0.0))

    # Stamps.
    small_bag(out, 'duplicate_joint_stamp', joints=lambda k, ns: joint_state(k, ns - 10 * MS if k == 5 else ns))
    small_bag(out, 'decreasing_truth_stamp',
              truth=lambda k, ns: pose_stamped(ns - 80 * MS if k == 2 else ns, 'map', 0.0, 0.0, 0.0))

    # Too few samples.
    small_bag(out, 'zero_joint_messages', joints=lambda k, ns: None)
    small_bag(out, 'one_joint_message', joints=lambda k, ns: joint_state(k, ns) if k == 0 else None)
    small_bag(out, 'one_truth_pose', truth=lambda k, ns: pose_stamped(ns, 'map', 0.0, 0.0, 0.0) if k == 1 else None)

    # Absurd values.
    small_bag(out, 'absurd_velocity', joints=lambda k, ns: joint_state(k, ns, velocity=[1.0, -2.0e7, 0.0])
              if k == 8 else joint_state(k, ns))
    small_bag(out, 'absurd_position', truth=lambda k, ns: pose_stamped(ns, 'map', 3.0e12 if k == 2 else 0.0, 0.0,
                                                                     0.0))

    # Missing ground truth, joints that do not match.
    small_bag(out, 'no_truth_messages', truth=lambda k, ns: None)
    small_bag(out, 'truth_after_wheels', truth=lambda k, ns: pose_stamped(ns + 10_000 * MS, 'map', 0.0, 0.0, 0.0))
    small_bag(out, 'truth_in_odom_frame', truth=lambda k, ns: pose_stamped(ns, 'odom', 0.0, 0.0, 0.0))
    small_bag(out, 'joint_names_mismatch',
              joints=lambda k, ns: joint_state(k, ns, names=['front_wheel', 'left_wheel', 'right_wheel']))

    for p in tmp.iterdir():
        p.unlink()
    tmp.rmdir()


CSV_HEADER = 't_s,wheel_a_rad_s,wheel_b_rad_s,wheel_c_rad_s,x_m,y_m,theta_rad'


def csv_rows(n=6, nl='\n', **replace):
    """A valid run of n rows; `replace[k] = text` swaps in row k (0-based)."""
    rows = [f'{0.01 * k:.2f},{1.0 + 0.1 * k},-0.5,-0.5,{0.001 * k},0,{0.01 * k}' for k in range(n)]
    for k, text in replace.items():
        rows[int(k[1:])] = text
    return nl.join(rows) + nl


def csv_corpus(out):
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob('*.csv'):
        old.unlink()
    files = {
        'empty.csv': '',
        'comments_only.csv': '# omnical run v1\n# name: x\n',
        'header_only.csv': CSV_HEADER + '\n',
        'one_sample.csv': CSV_HEADER + '\n' + csv_rows(1),
        'missing_t_s.csv': CSV_HEADER.replace('t_s,', 'time,') + '\n' + csv_rows(),
        'missing_theta.csv': CSV_HEADER.replace(',theta_rad', '') + '\n' + csv_rows(),
        'no_wheel_columns.csv': 't_s,x_m,y_m,theta_rad\n0,0,0,0\n0.01,0,0,0\n',
        'ticks_without_ticks_per_rev.csv': 't_s,a_ticks,b_ticks,c_ticks,x_m,y_m,theta_rad\n0,0,0,0,0,0,0\n',
        'bad_number.csv': CSV_HEADER + '\n' + csv_rows(r3='0.03,1.3,-0.5,-0.5,0.003,0,0.0.3'),
        'comma_decimal.csv': CSV_HEADER + '\n' + csv_rows(r2='0.02,"1,2",-0.5,-0.5,0.002,0,0.02'),
        'nan_wheel.csv': CSV_HEADER + '\n' + csv_rows(r4='0.04,NaN,-0.5,-0.5,0.004,0,0.04'),
        'inf_pose.csv': CSV_HEADER + '\n' + csv_rows(r1='0.01,1.1,-0.5,-0.5,inf,0,0.01'),
        'ragged_row.csv': CSV_HEADER + '\n' + csv_rows(r2='0.02,1.2,-0.5,-0.5,0.002,0,0.02,99'),
        'partly_filled.csv': CSV_HEADER + '\n' + csv_rows(r3='0.03,1.3,,-0.5,0.003,0,0.03'),
        'duplicate_t.csv': CSV_HEADER + '\n' + csv_rows(r3='0.02,1.3,-0.5,-0.5,,,'),
        'decreasing_t.csv': CSV_HEADER + '\n' + csv_rows(r4='0.01,1.4,-0.5,-0.5,0.004,0,0.04'),
        'no_truth.csv': CSV_HEADER + '\n' + ''.join(f'{0.01 * k:.2f},1,-0.5,-0.5,,,\n' for k in range(5)),
        'absurd_wheel.csv': CSV_HEADER + '\n' + csv_rows(r2='0.02,3e9,-0.5,-0.5,0.002,0,0.02'),
        'absurd_heading.csv': CSV_HEADER + '\n' + csv_rows(r5='0.05,1.5,-0.5,-0.5,0.005,0,1e30'),
        'bad_repetition.csv': '# repetition: -1\n' + CSV_HEADER + '\n' + csv_rows(),
        'partial_command.csv': '# command_v_m_s: 0.2\n' + CSV_HEADER + '\n' + csv_rows(),
        # BOM and CRLF must be read through, with the right line numbers and no stray characters.
        'bom_missing_column.csv': '\ufeff' + CSV_HEADER.replace(',y_m', '') + '\n' + csv_rows(),
        'crlf_bad_number.csv': '# omnical run v1\r\n' + CSV_HEADER + '\r\n'
                               + csv_rows(nl='\r\n', r2='0.02,1.2,-0.5,-0.5,x,0,0.02'),
        'bom_crlf_decreasing_t.csv': '\ufeff' + CSV_HEADER + '\r\n' + csv_rows(nl='\r\n', r5='0.00,1,1,1,,,'),
    }
    for name, text in files.items():
        (out / name).write_bytes(text.encode())
    (out / 'utf16.csv').write_bytes((CSV_HEADER + '\n' + csv_rows()).encode('utf-16'))
    (out / 'binary.csv').write_bytes(bytes(range(256)) * 2)


def main():
    mcap_corpus(HERE / 'mcap')
    csv_corpus(HERE / 'csv')
    return 0


if __name__ == '__main__':
    sys.exit(main())
