#!/usr/bin/env python3
"""Copies every bare .mcap file of a folder into a rosbag2 recording folder with Python rosbags, for the
loading benchmark (benches/loading.sh): the same messages (CDR bytes copied as they are) in another storage.

    mcap_to_rosbag2.py SRC_DIR DST_DIR sqlite3|mcap

Each SRC_DIR/<name>.mcap becomes DST_DIR/<name>/ (metadata.yaml + <name>.db3 or <name>.mcap). Other files
(robot.toml) are copied as they are. Needs: pip install rosbags
"""

import shutil
import sys
from pathlib import Path

from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore


def main(src, dst, storage):
    src, dst = Path(src), Path(dst)
    shutil.rmtree(dst, ignore_errors=True)
    dst.mkdir(parents=True)
    plugin = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}[storage]
    store = get_typestore(Stores.ROS2_HUMBLE)
    for f in sorted(src.iterdir()):
        if f.suffix != '.mcap':
            if f.is_file():
                shutil.copy(f, dst / f.name)
            continue
        with AnyReader([f], default_typestore=store) as reader, \
                Writer(dst / f.stem, version=9, storage_plugin=plugin) as writer:
            conns = {}
            for c in reader.connections:
                conns[c.id] = writer.add_connection(c.topic, c.msgtype, typestore=reader.typestore)
            for c, t, data in reader.messages():
                writer.write(conns[c.id], t, data)


if __name__ == '__main__':
    main(*sys.argv[1:4])
