// Writes the issue #41 benchmark bag: one sensor_msgs/msg/Imu topic (/imu/data) at 400 Hz for
// HOURS hours (default 3: 4,320,000 messages) in MCAP with zstd chunks, by foxglove's own
// writers: @mcap/core's McapWriter for the container (profile ros2, 768 KiB chunks as
// rosbag2_storage_mcap's default, summary with chunk indexes and statistics), zstd level 3
// (@foxglove/wasm-zstd, zstd's default level), CDR payloads by
// @foxglove/rosmsg2-serialization. Values: white noise from a seeded generator
// (mulberry32 + Box-Muller): gyro sigma 1e-3 rad/s, accel sigma 1e-2 m/s^2 about
// (0, 0, 9.80665); stamps exactly 2.5 ms apart, log time = stamp + 1.5 ms. metro's code is
// not used. The file is written by bench/ros/run.sh at bench time and never committed.
// Usage: node write_imu_bag.mjs OUT.mcap [HOURS]
import { McapWriter } from "@mcap/core";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import { parse } from "@foxglove/rosmsg";
import * as zstd from "@foxglove/wasm-zstd";
import { openSync, writeSync, closeSync } from "node:fs";

const IMU_DEF = `std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
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
`;

const [out, hoursText = "3"] = process.argv.slice(2);
if (!out) {
  console.error("usage: node write_imu_bag.mjs OUT.mcap [HOURS]");
  process.exit(2);
}
const count = Math.round(Number(hoursText) * 3600 * 400);

function mulberry32(seed) {
  return () => {
    seed = (seed + 0x6d2b79f5) | 0;
    let t = seed;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}
const rnd = mulberry32(41);
function gauss() {
  const u = 1 - rnd();
  return Math.sqrt(-2 * Math.log(u)) * Math.cos(2 * Math.PI * rnd());
}

// A writable that appends to a file (McapWriter's IWritable).
class FileWritable {
  constructor(path) {
    this.fd = openSync(path, "w");
    this.offset = 0n;
  }
  position() {
    return this.offset;
  }
  async write(buffer) {
    let done = 0;
    while (done < buffer.byteLength) done += writeSync(this.fd, buffer, done);
    this.offset += BigInt(buffer.byteLength);
  }
  close() {
    closeSync(this.fd);
  }
}

await zstd.isLoaded;
const file = new FileWritable(out);
const writer = new McapWriter({
  writable: file,
  chunkSize: 768 * 1024,
  compressChunk: (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) }),
});
await writer.start({ profile: "ros2", library: "@mcap/core (metro bench writer)" });
const schemaId = await writer.registerSchema({
  name: "sensor_msgs/msg/Imu", encoding: "ros2msg", data: new TextEncoder().encode(IMU_DEF) });
const channelId = await writer.registerChannel({
  topic: "/imu/data", messageEncoding: "cdr", schemaId, metadata: new Map() });
const imu = new MessageWriter(parse(IMU_DEF, { ros2: true }));
const cov = (s) => [s, 0, 0, 0, s, 0, 0, 0, s];
const t0 = 1700000000n * 1000000000n;
const m = {
  header: { stamp: { sec: 0, nanosec: 0 }, frame_id: "imu" },
  orientation: { x: 0, y: 0, z: 0, w: 0 },
  orientation_covariance: [-1, 0, 0, 0, 0, 0, 0, 0, 0],
  angular_velocity: { x: 0, y: 0, z: 0 },
  angular_velocity_covariance: cov(1e-6),
  linear_acceleration: { x: 0, y: 0, z: 0 },
  linear_acceleration_covariance: cov(1e-4),
};
for (let k = 0; k < count; ++k) {
  const stamp = t0 + BigInt(k) * 2500000n;
  m.header.stamp.sec = Number(stamp / 1000000000n);
  m.header.stamp.nanosec = Number(stamp % 1000000000n);
  m.angular_velocity.x = 1e-3 * gauss();
  m.angular_velocity.y = 1e-3 * gauss();
  m.angular_velocity.z = 1e-3 * gauss();
  m.linear_acceleration.x = 1e-2 * gauss();
  m.linear_acceleration.y = 1e-2 * gauss();
  m.linear_acceleration.z = 9.80665 + 1e-2 * gauss();
  const logTime = stamp + 1500000n;
  await writer.addMessage({ channelId, sequence: k, logTime, publishTime: logTime,
                            data: imu.writeMessage(m) });
}
await writer.end();
file.close();
console.error(`${out}: ${count} messages, ${file.offset} bytes`);
