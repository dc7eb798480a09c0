// Writes metro's MCAP test files with foxglove's own writers (@mcap/core for the container,
// @foxglove/rosmsg2-serialization for the ROS 2 CDR payloads, @foxglove/wasm-zstd and lz4js
// for the chunk codecs), and beside each file a JSON of what was written (expected values).
// Run: cd datasets/external/ros_samples/tools && npm ci && node write_mcap.mjs
// metro's code is not used; the numbers come from a seeded PRNG (mulberry32).
import { McapWriter, TempBuffer } from "@mcap/core";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import { parse } from "@foxglove/rosmsg";
import * as zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";
import { mkdirSync, writeFileSync } from "node:fs";

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
const TEMP_DEF = `std_msgs/Header header
float64 temperature
float64 variance
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
`;

function mulberry32(seed) {
  return () => {
    seed = (seed + 0x6d2b79f5) | 0;
    let t = seed;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

const imuWriter = new MessageWriter(parse(IMU_DEF, { ros2: true }));
const tempWriter = new MessageWriter(parse(TEMP_DEF, { ros2: true }));

// One IMU message: stamp = t0 + k * period (+ `jitter_ns` of message k), values from rnd.
function imuMessage(rnd, stampNs, withOrientation, frame) {
  const cov = (s) => [s, 0, 0, 0, s, 0, 0, 0, s];
  const q = [rnd() - 0.5, rnd() - 0.5, rnd() - 0.5, rnd() + 0.5];
  const n = Math.hypot(...q);
  return {
    header: {
      stamp: { sec: Number(stampNs / 1000000000n), nanosec: Number(stampNs % 1000000000n) },
      frame_id: frame,
    },
    orientation: withOrientation
      ? { x: q[0] / n, y: q[1] / n, z: q[2] / n, w: q[3] / n }
      : { x: 0, y: 0, z: 0, w: 0 },
    orientation_covariance: withOrientation ? cov(1e-4) : [-1, 0, 0, 0, 0, 0, 0, 0, 0],
    angular_velocity: { x: (rnd() - 0.5) * 0.02, y: (rnd() - 0.5) * 0.02, z: (rnd() - 0.5) * 0.02 },
    angular_velocity_covariance: cov(2.5e-7),
    linear_acceleration: { x: (rnd() - 0.5) * 0.2, y: (rnd() - 0.5) * 0.2, z: 9.80665 + (rnd() - 0.5) * 0.2 },
    linear_acceleration_covariance: cov(4e-4),
  };
}

const compressors = {
  "": undefined,
  zstd: (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 19) }),
  lz4: (data) => ({ compression: "lz4", compressedData: lz4.compress(data) }),
};

// streams: [{topic, count, period_ns, t0_ns, orientation, swaps: [k...] (message k and k+1
// exchange stamps), dups: [k...] (message k+1 gets message k's stamp)}], plus a Temperature topic.
async function writeFile(name, options, streams, seed, expectedName = name.replace(/\.mcap$/, ".expected.json")) {
  const rnd = mulberry32(seed);
  const buffer = new TempBuffer();
  const writer = new McapWriter({
    writable: buffer,
    chunkSize: 4 * 1024,
    compressChunk: compressors[options.compression ?? ""],
    ...options.writer,
  });
  await writer.start({ profile: "ros2", library: "@mcap/core (metro test writer)" });
  const imuSchema = await writer.registerSchema({
    name: "sensor_msgs/msg/Imu", encoding: "ros2msg", data: new TextEncoder().encode(IMU_DEF) });
  const tempSchema = await writer.registerSchema({
    name: "sensor_msgs/msg/Temperature", encoding: "ros2msg", data: new TextEncoder().encode(TEMP_DEF) });
  const expected = { file: name, topics: {} };
  const queue = [];
  for (const s of streams) {
    const id = await writer.registerChannel({
      topic: s.topic, messageEncoding: "cdr", schemaId: imuSchema, metadata: new Map() });
    const stamps = [];
    for (let k = 0; k < s.count; ++k) stamps.push(s.t0_ns + BigInt(k) * s.period_ns);
    for (const k of s.swaps ?? []) [stamps[k], stamps[k + 1]] = [stamps[k + 1], stamps[k]];
    for (const k of s.dups ?? []) stamps[k + 1] = stamps[k];
    const rows = [];
    for (let k = 0; k < s.count; ++k) {
      const m = imuMessage(rnd, stamps[k], s.orientation, s.topic.replace(/^\//, ""));
      // Log (receive) time: the stamp's nominal time plus 1.5 ms of transport.
      const logNs = s.t0_ns + BigInt(k) * s.period_ns + 1500000n;
      queue.push({ channelId: id, sequence: k, logTime: logNs, publishTime: logNs,
                   data: imuWriter.writeMessage(m) });
      rows.push({ stamp_ns: stamps[k].toString(), log_time_ns: logNs.toString(),
                  orientation_xyzw: [m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w],
                  orientation_covariance: m.orientation_covariance,
                  angular_velocity: [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z],
                  angular_velocity_covariance: m.angular_velocity_covariance,
                  linear_acceleration: [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z],
                  linear_acceleration_covariance: m.linear_acceleration_covariance });
    }
    expected.topics[s.topic] = { type: "sensor_msgs/msg/Imu", messages: rows };
  }
  const tempId = await writer.registerChannel({
    topic: "/imu/temperature", messageEncoding: "cdr", schemaId: tempSchema, metadata: new Map() });
  const t0 = streams[0].t0_ns;
  for (let k = 0; k < 5; ++k) {
    const logNs = t0 + BigInt(k) * 100000000n + 700000n;
    queue.push({ channelId: tempId, sequence: k, logTime: logNs, publishTime: logNs,
                 data: tempWriter.writeMessage({ header: { stamp: { sec: Number(logNs / 1000000000n),
                   nanosec: Number(logNs % 1000000000n) }, frame_id: "imu" },
                   temperature: 30 + rnd(), variance: 0.01 }) });
  }
  expected.topics["/imu/temperature"] = { type: "sensor_msgs/msg/Temperature", count: 5 };
  // Messages in log-time order, as a recorder writes them.
  queue.sort((a, b) => (a.logTime < b.logTime ? -1 : a.logTime > b.logTime ? 1 : 0));
  for (const m of queue) await writer.addMessage(m);
  await writer.end();
  writeFileSync("../" + name, buffer.get());
  writeFileSync("../" + expectedName, JSON.stringify(expected) + "\n");
}

await zstd.isLoaded;
const T0 = 1700000000n * 1000000000n + 123456789n;
const one = (o = {}) => [{ topic: "/imu/data", count: 60, period_ns: 5000000n, t0_ns: T0,
                            orientation: true, ...o }];
const noSummary = { useSummaryOffsets: false, useStatistics: false, useChunkIndex: false,
                    useMessageIndex: false, repeatSchemas: false, repeatChannels: false,
                    useAttachmentIndex: false, useMetadataIndex: false };
await writeFile("imu_zstd.mcap", { compression: "zstd" }, one(), 1);
await writeFile("imu_lz4.mcap", { compression: "lz4" }, one(), 2);
await writeFile("imu_none_nosummary.mcap", { writer: noSummary }, one({ orientation: false }), 3);
await writeFile("imu_unchunked.mcap", { writer: { useChunks: false } }, one(), 4);
await writeFile("two_imus_zstd.mcap", { compression: "zstd" },
  [{ topic: "/imu0", count: 48, period_ns: 5000000n, t0_ns: T0, orientation: false,
     swaps: [10, 30], dups: [40] },
   { topic: "/imu1", count: 24, period_ns: 10000000n, t0_ns: T0 + 2000000n, orientation: true }], 5);

// A ROS 2 bag folder with MCAP storage (rosbag2_storage_mcap): metadata.yaml (rosbag2's
// version 5 layout, written here) and one zstd-chunked file.
mkdirSync("../rosbag2_mcap", { recursive: true });
await writeFile("rosbag2_mcap/rosbag2_mcap_0.mcap", { compression: "zstd" }, one(), 6,
                "rosbag2_mcap.expected.json");
writeFileSync("../rosbag2_mcap/metadata.yaml", `rosbag2_bagfile_information:
  version: 5
  storage_identifier: mcap
  duration:
    nanoseconds: ${59n * 5000000n}
  starting_time:
    nanoseconds_since_epoch: ${T0 + 700000n}
  message_count: 65
  topics_with_message_count:
    - topic_metadata:
        name: /imu/data
        type: sensor_msgs/msg/Imu
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: 60
    - topic_metadata:
        name: /imu/temperature
        type: sensor_msgs/msg/Temperature
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: 5
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - rosbag2_mcap_0.mcap
`);
