#!/usr/bin/env python3
# Writes metro's ROS 2 sqlite3 bag (a folder with metadata.yaml and one .db3) with Python's
# standard library: the tables of rosbag2_storage_default_plugins (rosbag2 Humble's schema,
# sqlite_storage.cpp) and CDR payloads encoded here with struct following OMG DDS-XTypes
# 1.3 7.4.1 (encapsulation 00 01 00 00 = CDR little endian; each primitive aligned to its
# size from the end of the encapsulation; strings as uint32 length with the NUL, bytes,
# NUL). A JSON of what was written goes beside it. metro's code is not used.
# Run: python3 write_rosbag2_sqlite.py (from this folder).
import json
import os
import random
import sqlite3
import struct

T0_NS = 1700000000 * 10**9 + 123456789
NAME = "rosbag2_sqlite"


def align(buf, n):
    # Alignment counts from after the 4-byte encapsulation header.
    while (len(buf) - 4) % n:
        buf += b"\0"
    return buf


def cdr_string(buf, s):
    buf = align(buf, 4)
    raw = s.encode() + b"\0"
    return buf + struct.pack("<I", len(raw)) + raw


def cdr_imu(stamp_ns, frame, doubles):
    buf = b"\x00\x01\x00\x00"
    buf += struct.pack("<iI", stamp_ns // 10**9, stamp_ns % 10**9)
    buf = cdr_string(buf, frame)
    buf = align(buf, 8)
    return buf + struct.pack("<37d", *doubles)


def cdr_temperature(stamp_ns, frame, temperature, variance):
    buf = b"\x00\x01\x00\x00" + struct.pack("<iI", stamp_ns // 10**9, stamp_ns % 10**9)
    buf = align(cdr_string(buf, frame), 8)
    return buf + struct.pack("<2d", temperature, variance)


def main():
    rnd = random.Random(21)
    os.makedirs("../" + NAME, exist_ok=True)
    db_path = "../%s/%s_0.db3" % (NAME, NAME)
    if os.path.exists(db_path):
        os.remove(db_path)
    db = sqlite3.connect(db_path)
    db.executescript("""
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);
INSERT INTO schema VALUES(3, 'humble');
CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL, data BLOB NOT NULL);
CREATE INDEX timestamp_idx ON messages (timestamp ASC);
""")
    db.execute("INSERT INTO topics VALUES(1, '/imu/data', 'sensor_msgs/msg/Imu', 'cdr', '')")
    db.execute("INSERT INTO topics VALUES(2, '/imu/temperature', 'sensor_msgs/msg/Temperature', "
               "'cdr', '')")
    rows, count = [], 60
    for k in range(count):
        stamp = T0_NS + k * 5000000
        log_ns = stamp + 1500000
        q = [rnd.random() - 0.5, rnd.random() - 0.5, rnd.random() - 0.5, rnd.random() + 0.5]
        n = sum(v * v for v in q) ** 0.5
        q = [v / n for v in q]
        qc = [1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4]
        w = [(rnd.random() - 0.5) * 0.02 for _ in range(3)]
        wc = [2.5e-7, 0, 0, 0, 2.5e-7, 0, 0, 0, 2.5e-7]
        a = [(rnd.random() - 0.5) * 0.2 for _ in range(3)]
        a[2] = 9.80665 + a[2]
        ac = [4e-4, 0, 0, 0, 4e-4, 0, 0, 0, 4e-4]
        data = cdr_imu(stamp, "imu", q + qc + w + wc + a + ac)
        db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES(1, ?, ?)", (log_ns, data))
        rows.append({"stamp_ns": str(stamp), "log_time_ns": str(log_ns), "orientation_xyzw": q,
                     "orientation_covariance": qc, "angular_velocity": w,
                     "angular_velocity_covariance": wc, "linear_acceleration": a,
                     "linear_acceleration_covariance": ac})
        if k % 12 == 0:
            db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES(2, ?, ?)",
                       (log_ns, cdr_temperature(log_ns, "imu", 30 + rnd.random(), 0.01)))
    db.commit()
    db.close()
    temps = (count + 11) // 12
    with open("../%s/metadata.yaml" % NAME, "w") as f:
        f.write("""rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  duration:
    nanoseconds: %d
  starting_time:
    nanoseconds_since_epoch: %d
  message_count: %d
  topics_with_message_count:
    - topic_metadata:
        name: /imu/data
        type: sensor_msgs/msg/Imu
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: %d
    - topic_metadata:
        name: /imu/temperature
        type: sensor_msgs/msg/Temperature
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: %d
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - %s_0.db3
  files:
    - path: %s_0.db3
      starting_time:
        nanoseconds_since_epoch: %d
      duration:
        nanoseconds: %d
      message_count: %d
""" % ((count - 1) * 5000000, T0_NS + 1500000, count + temps, count, temps, NAME, NAME,
       T0_NS + 1500000, (count - 1) * 5000000, count + temps))
    expected = {"file": NAME, "topics": {
        "/imu/data": {"type": "sensor_msgs/msg/Imu", "messages": rows},
        "/imu/temperature": {"type": "sensor_msgs/msg/Temperature", "count": temps}}}
    with open("../%s.expected.json" % NAME, "w") as f:
        json.dump(expected, f)
        f.write("\n")


main()
