#!/usr/bin/env node
// Writes a deterministic rosbag2-style ROS 2 MCAP recording with @mcap/core's McapWriter,
// plus OUT.mcap.expected.jsonl (one line per message, log-time order).
//
// usage: node write_mcap.mjs OUT.mcap [--compression none|zstd|lz4] [--chunk-size BYTES]
//                           [--big-endian-scan] [--qos-style jazzy|humble]
import fs from "node:fs";
import { McapWriter } from "@mcap/core";
import { parse as parseMsgDef } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import { CdrWriter, EncapsulationKind } from "@foxglove/cdr";
import zstd from "@foxglove/wasm-zstd";
import lz4js from "lz4js";
import { ros2msgDefinition } from "./msgdefs.mjs";
import { jsonlLine } from "./jsonl.mjs";

function usage(msg) {
  if (msg) console.error(`write_mcap.mjs: ${msg}`);
  console.error(
    "usage: node write_mcap.mjs OUT.mcap [--compression none|zstd|lz4] [--chunk-size BYTES] [--big-endian-scan] [--qos-style jazzy|humble]",
  );
  process.exit(2);
}

// ---- arguments ----
const args = process.argv.slice(2);
let out;
let compression = "none";
let chunkSize = 32 * 1024;
let bigEndianScan = false;
let qosStyle = "jazzy";
for (let i = 0; i < args.length; i++) {
  const a = args[i];
  const value = () => (i + 1 < args.length ? args[++i] : usage(`${a} needs a value`));
  if (a === "--compression") compression = value();
  else if (a === "--chunk-size") chunkSize = Number(value());
  else if (a === "--big-endian-scan") bigEndianScan = true;
  else if (a === "--qos-style") qosStyle = value();
  else if (a === "-h" || a === "--help") usage();
  else if (a.startsWith("-")) usage(`unknown option ${a}`);
  else if (out === undefined) out = a;
  else usage(`unexpected argument ${a}`);
}
if (!out) usage("missing OUT.mcap");
if (!["none", "zstd", "lz4"].includes(compression)) usage(`bad --compression ${compression}`);
if (!Number.isInteger(chunkSize) || chunkSize <= 0) usage("bad --chunk-size");
if (!["jazzy", "humble"].includes(qosStyle)) usage(`bad --qos-style ${qosStyle}`);

// ---- QoS metadata as rosbag2 stores it (YAML::Dump of a sequence of profiles) ----
function qosYaml({ reliability = "reliable", durability = "volatile" } = {}) {
  const inf = "\n    sec: 9223372036\n    nsec: 854775807";
  // Jazzy (metadata version >= 9) writes policy names; Humble writes rmw enum integers.
  const humble = qosStyle === "humble";
  const rel = humble ? { reliable: 1, best_effort: 2 }[reliability] : reliability;
  const dur = humble ? { transient_local: 1, volatile: 2 }[durability] : durability;
  return (
    `- history: ${humble ? 3 : "unknown"}\n` +
    `  depth: 0\n` +
    `  reliability: ${rel}\n` +
    `  durability: ${dur}\n` +
    `  deadline:${inf}\n` +
    `  lifespan:${inf}\n` +
    `  liveliness: ${humble ? 1 : "automatic"}\n` +
    `  liveliness_lease_duration:${inf}\n` +
    `  avoid_ros_namespace_conventions: false`
  );
}

// ---- time helpers ----
const NS = 1_000_000_000n;
const T0 = 1_700_000_000n * NS + 123_456_789n;
const MS = 1_000_000n;
const stamp = (ns) => ({ sec: Number(ns / NS), nanosec: Number(ns % NS) });
const secondsSinceStart = (ns) => Number(ns - T0) / 1e9;
const f32 = Math.fround;
const yawQuat = (yaw) => ({ x: 0, y: 0, z: Math.sin(yaw / 2), w: Math.cos(yaw / 2) });

// Robot drives a gentle arc: v = 0.5 m/s, omega = 0.1 rad/s.
const V = 0.5;
const W = 0.1;
function poseAt(t) {
  const yaw = W * t;
  return { x: (V / W) * Math.sin(yaw), y: (V / W) * (1 - Math.cos(yaw)), yaw };
}

// ---- the recording: [topic, type, qos, [{logTime, msg}]] ----
const topics = [];
function topic(name, type, qos, messages) {
  topics.push({ name, type, qos, messages });
}

topic("/tf_static", "tf2_msgs/msg/TFMessage", { durability: "transient_local" }, [
  {
    logTime: T0,
    msg: {
      transforms: [
        {
          header: { stamp: stamp(T0), frame_id: "base_link" },
          child_frame_id: "laser",
          transform: { translation: { x: 0.2, y: -0.1, z: 0 }, rotation: yawQuat(0.3) },
        },
      ],
    },
  },
]);

const odomMsgs = [];
const tfMsgs = [];
for (let i = 0; i < 100; i++) {
  // /odom at 25 Hz starting 0.5 ms after T0
  {
    const t = T0 + 500_000n + BigInt(i) * 40n * MS;
    const p = poseAt(secondsSinceStart(t));
    const poseCov = new Array(36).fill(0);
    [0.01, 0.01, 1e6, 1e6, 1e6, 0.05].forEach((v, k) => (poseCov[k * 7] = v + i * 1e-4));
    poseCov[1] = poseCov[6] = 0.001;
    const twistCov = new Array(36).fill(0);
    [0.002, 0.002, 1e3, 1e3, 1e3, 0.01].forEach((v, k) => (twistCov[k * 7] = v));
    twistCov[5] = twistCov[30] = -0.0005;
    odomMsgs.push({
      logTime: t,
      msg: {
        header: { stamp: stamp(t), frame_id: "odom" },
        child_frame_id: "base_link",
        pose: {
          pose: { position: { x: p.x, y: p.y, z: 0 }, orientation: yawQuat(p.yaw) },
          covariance: poseCov,
        },
        twist: {
          twist: { linear: { x: V, y: 0, z: 0 }, angular: { x: 0, y: 0, z: W } },
          covariance: twistCov,
        },
      },
    });
  }
  // /tf at 25 Hz starting 1 ms after T0; every 10th message also carries map->odom
  {
    const t = T0 + 1n * MS + BigInt(i) * 40n * MS;
    const p = poseAt(secondsSinceStart(t));
    const transforms = [
      {
        header: { stamp: stamp(t), frame_id: "odom" },
        child_frame_id: "base_link",
        transform: { translation: { x: p.x, y: p.y, z: 0 }, rotation: yawQuat(p.yaw) },
      },
    ];
    if (i % 10 === 0) {
      transforms.push({
        header: { stamp: stamp(t), frame_id: "map" },
        child_frame_id: "odom",
        transform: { translation: { x: 1.0, y: 2.0, z: 0 }, rotation: yawQuat(0.05) },
      });
    }
    tfMsgs.push({ logTime: t, msg: { transforms } });
  }
}
topic("/tf", "tf2_msgs/msg/TFMessage", {}, tfMsgs);
topic("/odom", "nav_msgs/msg/Odometry", {}, odomMsgs);

// /scan at 10 Hz starting 5 ms after T0: 180 beams over [-pi/2, pi/2]
const scanMsgs = [];
const BEAMS = 180;
for (let s = 0; s < 40; s++) {
  const t = T0 + 5n * MS + BigInt(s) * 100n * MS;
  const ranges = new Float32Array(BEAMS);
  const intensities = new Float32Array(BEAMS);
  for (let b = 0; b < BEAMS; b++) {
    let r = 2 + 1.5 * Math.sin(b * 0.05 + s * 0.1) + 0.3 * Math.cos(b * 0.17);
    if ((b * 7 + s) % 53 === 0) r = NaN;
    else if ((b + 3 * s) % 61 === 0) r = Infinity;
    ranges[b] = r;
    intensities[b] = 100 + (b % 10) * 5 + s + 0.25;
  }
  scanMsgs.push({
    logTime: t,
    msg: {
      header: { stamp: stamp(t), frame_id: "laser" },
      angle_min: f32(-Math.PI / 2),
      angle_max: f32(-Math.PI / 2 + 179 * (Math.PI / 179)),
      angle_increment: f32(Math.PI / 179),
      time_increment: f32(1e-4),
      scan_time: f32(0.1),
      range_min: f32(0.05),
      range_max: f32(30),
      ranges,
      intensities,
    },
  });
}
topic("/scan", "sensor_msgs/msg/LaserScan", { reliability: "best_effort" }, scanMsgs);

// /imu at 50 Hz starting 2 ms after T0; orientation unknown (cov[0] = -1) in every other message
const imuMsgs = [];
for (let i = 0; i < 200; i++) {
  const t = T0 + 2n * MS + BigInt(i) * 20n * MS;
  const ts = secondsSinceStart(t);
  const known = i % 2 === 1;
  imuMsgs.push({
    logTime: t,
    msg: {
      header: { stamp: stamp(t), frame_id: "imu_link" },
      orientation: known ? yawQuat(W * ts) : { x: 0, y: 0, z: 0, w: 1 },
      orientation_covariance: known ? [0.0025, 0, 0, 0, 0.0025, 0, 0, 0, 0.0025] : [-1, 0, 0, 0, 0, 0, 0, 0, 0],
      angular_velocity: { x: 0.001 * Math.sin(ts), y: -0.002, z: W + 0.01 * Math.sin(3 * ts) },
      angular_velocity_covariance: [1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4],
      linear_acceleration: { x: 0.05 * Math.cos(ts), y: V * W, z: 9.80665 },
      linear_acceleration_covariance: [0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01],
    },
  });
}
topic("/imu", "sensor_msgs/msg/Imu", { reliability: "best_effort" }, imuMsgs);

// /joint_states at 10 Hz starting 7 ms after T0 (wheel radius 0.1 m, track 0.4 m)
const jsMsgs = [];
for (let i = 0; i < 40; i++) {
  const t = T0 + 7n * MS + BigInt(i) * 100n * MS;
  const ts = secondsSinceStart(t);
  const wl = (V - (W * 0.4) / 2) / 0.1;
  const wr = (V + (W * 0.4) / 2) / 0.1;
  jsMsgs.push({
    logTime: t,
    msg: {
      header: { stamp: stamp(t), frame_id: "" },
      name: ["left_wheel", "right_wheel"],
      position: [wl * ts, wr * ts],
      velocity: [wl, wr],
      effort: [],
    },
  });
}
topic("/joint_states", "sensor_msgs/msg/JointState", {}, jsMsgs);

// /chatter at 1 Hz starting 9 ms after T0
// ASCII only: @foxglove/cdr 3.5.0's CdrWriter.string() sizes strings by UTF-16 length and
// truncates non-ASCII text. The third string exercises JSON escaping (quote, backslash, tab).
const chatter = ["hello world 0", "", 'quote " backslash \\ tab \t end 2', "hello world 3"];
topic(
  "/chatter",
  "std_msgs/msg/String",
  {},
  chatter.map((data, i) => ({ logTime: T0 + 9n * MS + BigInt(i) * NS, msg: { data } })),
);

// ---- serialisation ----
function writeScanBigEndian(m) {
  const w = new CdrWriter({ kind: EncapsulationKind.CDR_BE });
  w.int32(m.header.stamp.sec);
  w.uint32(m.header.stamp.nanosec);
  w.string(m.header.frame_id);
  w.float32(m.angle_min);
  w.float32(m.angle_max);
  w.float32(m.angle_increment);
  w.float32(m.time_increment);
  w.float32(m.scan_time);
  w.float32(m.range_min);
  w.float32(m.range_max);
  w.float32Array(m.ranges, true);
  w.float32Array(m.intensities, true);
  return w.data;
}

// ---- write ----
class BufferWritable {
  chunks = [];
  length = 0n;
  position() {
    return this.length;
  }
  async write(buffer) {
    this.chunks.push(Buffer.from(buffer)); // copy: the writer reuses its buffers
    this.length += BigInt(buffer.byteLength);
  }
}

let compressChunk;
if (compression === "zstd") {
  await zstd.isLoaded;
  compressChunk = (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) });
} else if (compression === "lz4") {
  compressChunk = (data) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4js.compress(data)) });
}

const writable = new BufferWritable();
const writer = new McapWriter({ writable, chunkSize, compressChunk, startChannelId: 1 });
await writer.start({ profile: "ros2", library: "write_mcap.mjs" });

const schemaIds = new Map();
const all = [];
for (const tp of topics) {
  if (!schemaIds.has(tp.type)) {
    const text = ros2msgDefinition(tp.type);
    const id = await writer.registerSchema({
      name: tp.type,
      encoding: "ros2msg",
      data: new TextEncoder().encode(text),
    });
    schemaIds.set(tp.type, { id, serializer: new MessageWriter(parseMsgDef(text, { ros2: true })) });
  }
  const { id: schemaId, serializer } = schemaIds.get(tp.type);
  const channelId = await writer.registerChannel({
    topic: tp.name,
    schemaId,
    messageEncoding: "cdr",
    metadata: new Map([["offered_qos_profiles", qosYaml(tp.qos)]]),
  });
  tp.messages.forEach((m, seq) => {
    const data =
      bigEndianScan && tp.name === "/scan" ? writeScanBigEndian(m.msg) : serializer.writeMessage(m.msg);
    all.push({ topic: tp.name, type: tp.type, channelId, sequence: seq, logTime: m.logTime, msg: m.msg, data });
  });
}

all.sort((a, b) => (a.logTime < b.logTime ? -1 : a.logTime > b.logTime ? 1 : 0));
for (let i = 1; i < all.length; i++) {
  if (all[i].logTime === all[i - 1].logTime) throw new Error("internal: duplicate log time");
}
const lines = [];
for (const m of all) {
  await writer.addMessage({
    channelId: m.channelId,
    sequence: m.sequence,
    logTime: m.logTime,
    publishTime: m.logTime,
    data: m.data,
  });
  lines.push(jsonlLine(m.topic, m.logTime, m.type, m.msg));
}
await writer.end();

fs.writeFileSync(out, Buffer.concat(writable.chunks));
fs.writeFileSync(`${out}.expected.jsonl`, lines.join("\n") + "\n");
const counts = topics.map((t) => `${t.name}=${t.messages.length}`).join(" ");
console.log(
  `wrote ${out} (${writable.length} bytes, ${all.length} messages, ${writer.statistics?.chunkCount ?? "?"} chunks, ` +
    `compression ${compression}${bigEndianScan ? ", /scan big-endian CDR" : ""}, qos ${qosStyle}): ${counts}`,
);
