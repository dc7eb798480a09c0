#!/usr/bin/python3
# Writes metro's ROS 1 bag test files with Debian's rosbag (python3-rosbag 1.15.15, the ROS
# 1 recorder's own Python library) and genpy's message classes built from the
# sensor_msgs/Imu definition, and beside each bag a JSON of what was written.
# Run with Debian's interpreter: /usr/bin/python3 write_ros1_bags.py (from this folder).
# metro's code is not used; the numbers come from Python's random.Random(seed).
import json
import random
import struct

import genpy
import genpy.dynamic
import rosbag

IMU_DEF = """Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""
TEMP_DEF = """Header header
float64 temperature
float64 variance
================================================================================
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id
"""
Imu = genpy.dynamic.generate_dynamic("sensor_msgs/Imu", IMU_DEF)["sensor_msgs/Imu"]
Temperature = genpy.dynamic.generate_dynamic("sensor_msgs/Temperature",
                                             TEMP_DEF)["sensor_msgs/Temperature"]
assert Imu._md5sum == "6a62c6daae103f4ff57a132d6f95cec2", Imu._md5sum
T0_NS = 1700000000 * 10**9 + 123456789


def imu(rnd, seq, stamp_ns, frame):
    m = Imu()
    m.header.seq = seq
    m.header.stamp = genpy.Time(stamp_ns // 10**9, stamp_ns % 10**9)
    m.header.frame_id = frame
    q = [rnd.random() - 0.5, rnd.random() - 0.5, rnd.random() - 0.5, rnd.random() + 0.5]
    n = sum(v * v for v in q) ** 0.5
    m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w = [v / n for v in q]
    m.orientation_covariance = [1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4]
    m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = [
        (rnd.random() - 0.5) * 0.02 for _ in range(3)]
    m.angular_velocity_covariance = [2.5e-7, 0, 0, 0, 2.5e-7, 0, 0, 0, 2.5e-7]
    a = [(rnd.random() - 0.5) * 0.2 for _ in range(3)]
    m.linear_acceleration.x, m.linear_acceleration.y = a[0], a[1]
    m.linear_acceleration.z = 9.80665 + a[2]
    m.linear_acceleration_covariance = [4e-4, 0, 0, 0, 4e-4, 0, 0, 0, 4e-4]
    return m


def row(m, stamp_ns, log_ns):
    o, w, a = m.orientation, m.angular_velocity, m.linear_acceleration
    return {"stamp_ns": str(stamp_ns), "log_time_ns": str(log_ns),
            "orientation_xyzw": [o.x, o.y, o.z, o.w],
            "orientation_covariance": list(m.orientation_covariance),
            "angular_velocity": [w.x, w.y, w.z],
            "angular_velocity_covariance": list(m.angular_velocity_covariance),
            "linear_acceleration": [a.x, a.y, a.z],
            "linear_acceleration_covariance": list(m.linear_acceleration_covariance)}


def write(name, compression, seed, count=60, period_ns=5000000):
    rnd = random.Random(seed)
    rows = []
    with rosbag.Bag(name, "w", compression=compression, chunk_threshold=4096) as bag:
        for k in range(count):
            stamp = T0_NS + k * period_ns
            log_ns = stamp + 1500000  # 1.5 ms of transport.
            m = imu(rnd, k, stamp, "imu")
            bag.write("/imu/data", m, genpy.Time(log_ns // 10**9, log_ns % 10**9))
            rows.append(row(m, stamp, log_ns))
            if k % 12 == 0:
                t = Temperature()
                t.header.stamp = genpy.Time(log_ns // 10**9, log_ns % 10**9)
                t.temperature = 30 + rnd.random()
                bag.write("/imu/temperature", t, genpy.Time(log_ns // 10**9, log_ns % 10**9))
    expected = {"file": name, "topics": {
        "/imu/data": {"type": "sensor_msgs/Imu", "messages": rows},
        "/imu/temperature": {"type": "sensor_msgs/Temperature", "count": (count + 11) // 12}}}
    with open(name.replace(".bag", ".expected.json"), "w") as f:
        json.dump(expected, f)
        f.write("\n")


write("../ros1_none.bag", "none", 11)
write("../ros1_bz2.bag", "bz2", 12)
write("../ros1_lz4.bag", "lz4", 13)

# A bag whose recorder was killed: rosbag writes the index (connection and chunk info records
# from index_pos) and the bag header's index_pos only when the bag is closed. The closed
# bag's bytes up to index_pos, with the bag header as it is while recording (index_pos,
# conn_count and chunk_count 0), are what a killed recorder leaves behind (its last chunk
# complete).
with open("../ros1_lz4.bag", "rb") as f:
    data = f.read()
header_len = struct.unpack_from("<I", data, 13)[0]
fields, at = {}, 17
while at < 17 + header_len:
    n = struct.unpack_from("<I", data, at)[0]
    key, _, value = data[at + 4:at + 4 + n].partition(b"=")
    fields[key] = (at + 4 + len(key) + 1, value)
    at += 4 + n
index_pos = struct.unpack("<Q", fields[b"index_pos"][1])[0]
killed = bytearray(data[:index_pos])
for key, size in ((b"index_pos", 8), (b"conn_count", 4), (b"chunk_count", 4)):
    killed[fields[key][0]:fields[key][0] + size] = bytes(size)
with open("../ros1_noindex.bag", "wb") as f:
    f.write(killed)
