#!/bin/sh
# Cross-check of write_rosbag2_sqlite.py's hand-encoded CDR: every /imu/data payload of the
# .db3 decoded by @foxglove/rosmsg2-serialization's MessageReader must give the values of
# rosbag2_sqlite.expected.json. Run from this folder after npm ci.
set -e
python3 -c "
import sqlite3, json
db = sqlite3.connect('../rosbag2_sqlite/rosbag2_sqlite_0.db3')
print(json.dumps([r[0].hex() for r in db.execute('SELECT data FROM messages WHERE topic_id = 1 ORDER BY id')]))
" > /tmp/metro_sqlite_payloads.json
node --input-type=module -e "
import { MessageReader } from '@foxglove/rosmsg2-serialization';
import { parse } from '@foxglove/rosmsg';
import { readFileSync } from 'node:fs';
const src = readFileSync('write_mcap.mjs', 'utf8');
const def = src.slice(src.indexOf('\`') + 1, src.indexOf('\`', src.indexOf('\`') + 1));
const reader = new MessageReader(parse(def, { ros2: true }));
const payloads = JSON.parse(readFileSync('/tmp/metro_sqlite_payloads.json', 'utf8'));
const rows = JSON.parse(readFileSync('../rosbag2_sqlite.expected.json', 'utf8')).topics['/imu/data'].messages;
let bad = 0;
payloads.forEach((hex, k) => {
  const m = reader.readMessage(Buffer.from(hex, 'hex'));
  const r = rows[k];
  const got = [m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w,
               ...m.orientation_covariance, m.angular_velocity.x, m.angular_velocity.y,
               m.angular_velocity.z, ...m.angular_velocity_covariance, m.linear_acceleration.x,
               m.linear_acceleration.y, m.linear_acceleration.z, ...m.linear_acceleration_covariance];
  const want = [...r.orientation_xyzw, ...r.orientation_covariance, ...r.angular_velocity,
                ...r.angular_velocity_covariance, ...r.linear_acceleration, ...r.linear_acceleration_covariance];
  const stamp = BigInt(m.header.stamp.sec) * 1000000000n + BigInt(m.header.stamp.nanosec);
  if (got.some((v, i) => !Object.is(v, want[i])) || stamp.toString() !== r.stamp_ns || reader.lastReadHadTrailingBytes()) ++bad;
});
console.log(payloads.length + ' payloads, ' + bad + ' differ');
process.exit(bad ? 1 : 0);
"
