#!/usr/bin/env node
// Validates a rosbag2-style ROS 2 MCAP file with @mcap/core and @foxglove/rosmsg2-serialization.
//
// usage: node check_mcap.mjs IN.mcap [--jsonl OUT.jsonl] [--reencode]
//
// (a) McapStreamReader over the whole file (validateCrcs), every record, footer reached;
// (b) McapIndexedReader: summary, chunk indexes, statistics vs messages read, readMessages()
//     in log-time order, each chunk's message indexes against the chunk's contents,
//     data-section and summary CRCs when present;
// (c) profile "ros2", schema encoding "ros2msg", message encoding "cdr", offered_qos_profiles;
// (d) every message decoded with MessageReader built from @foxglove/rosmsg parse(text, {ros2: true});
// (e) with --reencode, every little-endian message serialised again from its decoded values with
//     rosmsg2-serialization's MessageWriter must be the same bytes (the golden bytes of the writer
//     that made the file: dispel's CDR encoder, the one dispel-ros2 publishes with).
// Exit 0 with a one-line summary, or 1 with "FAIL ...: reason".
import fs from "node:fs";
import zlib from "node:zlib";
import { McapIndexedReader, McapStreamReader, MCAP_MAGIC } from "@mcap/core";
import { parse as parseMsgDef } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "@foxglove/wasm-lz4";
import { jsonlLine } from "./jsonl.mjs";

const args = process.argv.slice(2);
let input;
let jsonlOut;
let reencode = false;
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--jsonl" && i + 1 < args.length) jsonlOut = args[++i];
  else if (args[i] === "--reencode") reencode = true;
  else if (!args[i].startsWith("-") && input === undefined) input = args[i];
  else {
    console.error("usage: node check_mcap.mjs IN.mcap [--jsonl OUT.jsonl] [--reencode]");
    process.exit(2);
  }
}
if (!input) {
  console.error("usage: node check_mcap.mjs IN.mcap [--jsonl OUT.jsonl]");
  process.exit(2);
}

class CheckError extends Error {}
function check(cond, msg) {
  if (!cond) throw new CheckError(typeof msg === "function" ? msg() : msg);
}

// ---- CRC-32 (zlib's; node >= 20.15 has zlib.crc32, otherwise a table) ----
const crc32 =
  typeof zlib.crc32 === "function"
    ? (data) => zlib.crc32(data) >>> 0
    : (() => {
        const table = new Uint32Array(256).map((_, n) => {
          let c = n;
          for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
          return c >>> 0;
        });
        return (data) => {
          let c = 0xffffffff;
          for (const b of data) c = table[(c ^ b) & 0xff] ^ (c >>> 8);
          return (c ^ 0xffffffff) >>> 0;
        };
      })();

// ---- decompression (MCAP "zstd" = zstd frame, "lz4" = LZ4 frame format) ----
function wrapHandler(name, fn) {
  return (buffer, size) => {
    let out;
    try {
      out = fn(buffer, Number(size));
    } catch (e) {
      throw new CheckError(`${name} decompression failed: ${e.message}`);
    }
    check(
      BigInt(out.byteLength) === BigInt(size),
      `${name} chunk decompressed to ${out.byteLength} bytes, chunk says uncompressed_size ${size}`,
    );
    return out;
  };
}
const decompressHandlers = {
  zstd: wrapHandler("zstd", (b, n) => zstd.decompress(b, n)),
  lz4: wrapHandler("lz4", (b, n) => lz4(b, n)),
};

// ---- little-endian helpers for the independent chunk / message-index walk ----
const u16 = (b, o) => b[o] | (b[o + 1] << 8);
const u32 = (b, o) => (b[o] | (b[o + 1] << 8) | (b[o + 2] << 16) | (b[o + 3] << 24)) >>> 0;
const u64 = (b, o) => BigInt(u32(b, o)) | (BigInt(u32(b, o + 4)) << 32n);
const OP = { MESSAGE: 0x05, CHUNK: 0x06, MESSAGE_INDEX: 0x07 };

function parseChunkRecord(b) {
  check(b[0] === OP.CHUNK, `expected Chunk opcode 0x06, found 0x${b[0]?.toString(16)}`);
  const len = Number(u64(b, 1));
  check(9 + len === b.length, `chunk record length ${len} disagrees with chunk_length ${b.length}`);
  let o = 9;
  const messageStartTime = u64(b, o);
  const messageEndTime = u64(b, o + 8);
  const uncompressedSize = u64(b, o + 16);
  const uncompressedCrc = u32(b, o + 24);
  o += 28;
  const clen = u32(b, o);
  const compression = Buffer.from(b.subarray(o + 4, o + 4 + clen)).toString("utf8");
  o += 4 + clen;
  const rlen = Number(u64(b, o));
  o += 8;
  check(o + rlen === b.length, `chunk records length ${rlen} does not fill the record`);
  return { messageStartTime, messageEndTime, uncompressedSize, uncompressedCrc, compression, records: b.subarray(o, o + rlen) };
}

const time = (t) => t.toString();

async function main() {
  const bytes = new Uint8Array(fs.readFileSync(input));
  const magic = Uint8Array.from(MCAP_MAGIC);
  check(bytes.length >= 2 * magic.length, `file too small (${bytes.length} bytes)`);
  check(
    magic.every((v, i) => bytes[i] === v),
    "file does not begin with the MCAP magic 89 4D 43 41 50 30 0D 0A",
  );
  check(
    magic.every((v, i) => bytes[bytes.length - magic.length + i] === v),
    "file does not end with the MCAP magic",
  );
  await zstd.isLoaded;
  await lz4.isLoaded;

  // ---------- (a) streaming read ----------
  const stream = new McapStreamReader({ includeChunks: true, decompressHandlers, validateCrcs: true });
  const recordCounts = {};
  const streamMessages = [];
  const streamChannels = new Map();
  const streamSchemas = new Map();
  let header;
  let footer;
  let dataEnd;
  const PIECE = 4096; // feed in pieces to exercise incremental parsing
  for (let off = 0; off < bytes.length && !stream.done(); off += PIECE) {
    try {
      stream.append(bytes.subarray(off, Math.min(bytes.length, off + PIECE)));
      for (let rec; (rec = stream.nextRecord()); ) {
        recordCounts[rec.type] = (recordCounts[rec.type] ?? 0) + 1;
        if (rec.type === "Header") header = rec;
        else if (rec.type === "Footer") footer = rec;
        else if (rec.type === "DataEnd") dataEnd = rec;
        else if (rec.type === "Schema") streamSchemas.set(rec.id, rec);
        else if (rec.type === "Channel") streamChannels.set(rec.id, rec);
        else if (rec.type === "Message")
          streamMessages.push(`${rec.channelId}|${rec.sequence}|${rec.logTime}|${rec.publishTime}|${crc32(rec.data)}|${rec.data.length}`);
        else if (rec.type === "Unknown") throw new CheckError(`unknown record opcode ${rec.opcode}`);
      }
    } catch (e) {
      if (e instanceof CheckError) throw e;
      throw new CheckError(`stream reader failed near byte ${off}: ${e.message}`);
    }
  }
  check(stream.done(), "stream reader did not reach a valid Footer and closing magic");
  check(header && footer, "Header or Footer record missing");
  check(dataEnd, "DataEnd record missing");

  // ---------- (b) indexed read ----------
  const fh = await fs.promises.open(input, "r");
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => {
      const buf = Buffer.alloc(Number(size));
      const { bytesRead } = await fh.read(buf, 0, Number(size), Number(offset));
      check(bytesRead === Number(size), `short read at ${offset}`);
      return buf;
    },
  };
  let reader;
  try {
    reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  } catch (e) {
    if (e instanceof CheckError) throw e;
    throw new CheckError(`McapIndexedReader.Initialize: ${e.message}`);
  }
  check(footer.summaryStart !== 0n, "no summary section (footer summary_start is 0)");
  const stats = reader.statistics;
  check(stats, "summary has no Statistics record");
  check(reader.channelsById.size > 0, "summary has no Channel records");
  check(
    stats.messageCount === 0n || reader.chunkIndexes.length > 0,
    "summary has no ChunkIndex records (file has messages)",
  );

  // summary schemas/channels agree with the data section
  for (const [id, ch] of reader.channelsById) {
    const s = streamChannels.get(id);
    check(s, `summary channel ${id} (${ch.topic}) not in data section`);
    check(
      s.topic === ch.topic && s.schemaId === ch.schemaId && s.messageEncoding === ch.messageEncoding &&
        JSON.stringify([...s.metadata]) === JSON.stringify([...ch.metadata]),
      `summary channel ${id} differs from the data-section copy`,
    );
  }
  check(streamChannels.size === reader.channelsById.size, "data section has channels missing in the summary");
  for (const [id, sc] of reader.schemasById) {
    const s = streamSchemas.get(id);
    check(s, `summary schema ${id} (${sc.name}) not in data section`);
    check(
      s.name === sc.name && s.encoding === sc.encoding && Buffer.compare(Buffer.from(s.data), Buffer.from(sc.data)) === 0,
      `summary schema ${id} differs from the data-section copy`,
    );
  }

  // summary offsets point at their groups
  for (const so of reader.summaryOffsetsByOpcode.values()) {
    const start = Number(so.groupStart);
    check(
      start >= Number(footer.summaryStart) && start + Number(so.groupLength) <= bytes.length - 8 - 29 &&
        bytes[start] === so.groupOpcode,
      `summary offset for opcode 0x${so.groupOpcode.toString(16)} does not point at such a record`,
    );
  }

  // data-section CRC (the readers do not verify it)
  let dataCrc = "absent";
  if (reader.dataSectionCrc !== undefined) {
    const actual = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
    check(actual === reader.dataSectionCrc, `data section CRC ${actual} != DataEnd's ${reader.dataSectionCrc}`);
    dataCrc = "ok";
  }
  const summaryCrc = footer.summaryCrc !== 0 ? "ok" : "absent"; // Initialize verified it

  // chunk indexes vs chunks vs message indexes
  let chunkCrcs = 0;
  const chunkCompressions = new Set();
  let prevChunkEnd = -1n;
  let chunksOverlap = false;
  for (const [ci, idx] of reader.chunkIndexes.entries()) {
    const where = `chunk ${ci} at ${idx.chunkStartOffset}`;
    const rec = parseChunkRecord(
      bytes.subarray(Number(idx.chunkStartOffset), Number(idx.chunkStartOffset + idx.chunkLength)),
    );
    chunkCompressions.add(rec.compression === "" ? "none" : rec.compression);
    check(rec.compression === idx.compression, `${where}: compression differs from chunk index`);
    check(BigInt(rec.records.length) === idx.compressedSize, `${where}: compressed_size differs from chunk index`);
    check(rec.uncompressedSize === idx.uncompressedSize, `${where}: uncompressed_size differs from chunk index`);
    check(
      rec.messageStartTime === idx.messageStartTime && rec.messageEndTime === idx.messageEndTime,
      `${where}: message start/end time differs from chunk index`,
    );
    let data = rec.records;
    if (rec.compression !== "") {
      const h = decompressHandlers[rec.compression];
      check(h, `${where}: unsupported compression "${rec.compression}"`);
      data = h(rec.records, rec.uncompressedSize);
    } else {
      check(BigInt(data.length) === rec.uncompressedSize, `${where}: uncompressed_size != records length`);
    }
    if (rec.uncompressedCrc !== 0) {
      check(crc32(data) === rec.uncompressedCrc, `${where}: uncompressed CRC mismatch`);
      chunkCrcs++;
    }
    // messages in the chunk
    const inChunk = new Map(); // channelId -> Map(offset -> logTime)
    let minT;
    let maxT;
    for (let o = 0; o < data.length; ) {
      check(o + 9 <= data.length, `${where}: truncated record inside chunk`);
      const op = data[o];
      const len = Number(u64(data, o + 1));
      check(o + 9 + len <= data.length, `${where}: record at ${o} overruns the chunk`);
      if (op === OP.MESSAGE) {
        const ch = u16(data, o + 9);
        const t = u64(data, o + 9 + 2 + 4);
        if (!inChunk.has(ch)) inChunk.set(ch, new Map());
        inChunk.get(ch).set(BigInt(o), t);
        minT = minT === undefined || t < minT ? t : minT;
        maxT = maxT === undefined || t > maxT ? t : maxT;
      }
      o += 9 + len;
    }
    check(
      minT === undefined || (minT === rec.messageStartTime && maxT === rec.messageEndTime),
      `${where}: message_start/end_time ${rec.messageStartTime}..${rec.messageEndTime} != messages' ${minT}..${maxT}`,
    );
    if (prevChunkEnd >= 0n && rec.messageStartTime < prevChunkEnd) chunksOverlap = true;
    prevChunkEnd = rec.messageEndTime;
    // message index records right after the chunk
    const miStart = Number(idx.chunkStartOffset + idx.chunkLength);
    const miEnd = miStart + Number(idx.messageIndexLength);
    const seenIdx = new Set();
    for (let o = miStart; o < miEnd; ) {
      check(bytes[o] === OP.MESSAGE_INDEX, `${where}: expected MessageIndex at ${o}, found opcode 0x${bytes[o].toString(16)}`);
      const len = Number(u64(bytes, o + 1));
      const ch = u16(bytes, o + 9);
      check(idx.messageIndexOffsets.get(ch) === BigInt(o), `${where}: chunk index offset for channel ${ch} is not ${o}`);
      const n = u32(bytes, o + 11);
      check(n % 16 === 0 && 2 + 4 + n === len, `${where}: malformed MessageIndex for channel ${ch}`);
      const expected = inChunk.get(ch) ?? new Map();
      check(n / 16 === expected.size, `${where}: MessageIndex of channel ${ch} has ${n / 16} entries, chunk has ${expected.size} messages`);
      for (let e = o + 15; e < o + 15 + n; e += 16) {
        const t = u64(bytes, e);
        const off = u64(bytes, e + 8);
        check(expected.get(off) === t, `${where}: MessageIndex entry (${t}, ${off}) of channel ${ch} matches no message`);
      }
      seenIdx.add(ch);
      o += 9 + len;
    }
    for (const ch of inChunk.keys()) check(seenIdx.has(ch), `${where}: channel ${ch} has messages but no MessageIndex`);
    check(
      idx.messageIndexOffsets.size === seenIdx.size,
      `${where}: chunk index lists ${idx.messageIndexOffsets.size} message indexes, found ${seenIdx.size}`,
    );
  }

  // ---------- (c) ROS 2 conventions ----------
  check(reader.header.profile === "ros2", `profile is "${reader.header.profile}", expected "ros2"`);
  for (const s of reader.schemasById.values()) {
    check(s.encoding === "ros2msg", `schema ${s.name}: encoding "${s.encoding}", expected "ros2msg"`);
    check(/^[A-Za-z]\w*\/\w+\/\w+$/.test(s.name), `schema name "${s.name}" is not pkg/msg/Type`);
  }
  const QOS_KEYS = [
    "history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
    "liveliness_lease_duration", "avoid_ros_namespace_conventions",
  ];
  for (const ch of reader.channelsById.values()) {
    check(ch.messageEncoding === "cdr", `channel ${ch.topic}: message encoding "${ch.messageEncoding}", expected "cdr"`);
    check(reader.schemasById.has(ch.schemaId), `channel ${ch.topic}: schema ${ch.schemaId} not in summary`);
    const qos = ch.metadata.get("offered_qos_profiles");
    check(qos !== undefined, `channel ${ch.topic}: no offered_qos_profiles metadata`);
    if (qos !== "") {
      check(/^- /.test(qos), `channel ${ch.topic}: offered_qos_profiles is not a YAML list`);
      for (const k of QOS_KEYS)
        check(new RegExp(`(^|\\n)[- ] *${k}:`).test(qos), `channel ${ch.topic}: offered_qos_profiles lacks "${k}"`);
    }
  }

  // ---------- (b, d) readMessages in log-time order, decode everything ----------
  const decoders = new Map();
  const encoders = new Map();
  const reencoded = new Map();  // schema name -> messages re-encoded to the same bytes
  for (const s of reader.schemasById.values()) {
    try {
      const defs = parseMsgDef(new TextDecoder().decode(s.data), { ros2: true });
      decoders.set(s.id, new MessageReader(defs));
      encoders.set(s.id, new MessageWriter(defs));
    } catch (e) {
      throw new CheckError(`schema ${s.name}: cannot parse ros2msg definition: ${e.message}`);
    }
  }
  const perChannel = new Map();
  const indexedMessages = [];
  const lines = [];
  let lastT = -1n;
  let bigEndian = 0;
  let minT;
  let maxT;
  try {
    for await (const m of reader.readMessages({ validateCrcs: true })) {
      const ch = reader.channelsById.get(m.channelId);
      check(ch, `message on unknown channel ${m.channelId}`);
      check(m.logTime >= lastT, `readMessages out of log-time order at ${ch.topic} ${m.logTime} < ${lastT}`);
      lastT = m.logTime;
      minT = minT === undefined || m.logTime < minT ? m.logTime : minT;
      maxT = maxT === undefined || m.logTime > maxT ? m.logTime : maxT;
      perChannel.set(m.channelId, (perChannel.get(m.channelId) ?? 0n) + 1n);
      indexedMessages.push(`${m.channelId}|${m.sequence}|${m.logTime}|${m.publishTime}|${crc32(m.data)}|${m.data.length}`);
      const schema = reader.schemasById.get(ch.schemaId);
      const where = `${ch.topic} message at log_time ${time(m.logTime)}`;
      check(m.data.length >= 4 && m.data[0] === 0 && (m.data[1] === 0 || m.data[1] === 1),
        () => `${where}: not plain CDR (encapsulation ${Buffer.from(m.data.subarray(0, 4)).toString("hex")})`);
      if (m.data[1] === 0) bigEndian++;
      const dec = decoders.get(ch.schemaId);
      let msg;
      try {
        msg = dec.readMessage(m.data);
      } catch (e) {
        throw new CheckError(`${where}: CDR decode as ${schema.name} failed: ${e.message}`);
      }
      const trailing = m.data.length - dec.lastReadByteLength();
      check(trailing <= 3, `${where}: ${trailing} bytes left after decoding as ${schema.name}`);
      if (reencode && m.data[1] === 1) {
        const again = encoders.get(ch.schemaId).writeMessage(msg);
        const n = Math.min(again.length, m.data.length);
        let at = 0;
        while (at < n && again[at] === m.data[at]) at++;
        check(at === again.length && at === m.data.length,
          () => `${where}: serialised again by rosmsg2-serialization, ${again.length} bytes that differ ` +
            `from the file's ${m.data.length} at byte ${at}`);
        reencoded.set(schema.name, (reencoded.get(schema.name) ?? 0) + 1);
      }
      if (jsonlOut) lines.push(jsonlLine(ch.topic, m.logTime, schema.name, msg));
    }
  } catch (e) {
    if (e instanceof CheckError) throw e;
    throw new CheckError(`readMessages: ${e.message}`);
  }

  // indexed and streamed messages are the same multiset
  check(indexedMessages.length === streamMessages.length,
    `indexed reader read ${indexedMessages.length} messages, stream reader ${streamMessages.length}`);
  const a = [...indexedMessages].sort();
  const b = [...streamMessages].sort();
  check(a.every((v, i) => v === b[i]), "indexed and streamed messages differ");

  // statistics
  const total = BigInt(indexedMessages.length);
  check(stats.messageCount === total, `Statistics message_count ${stats.messageCount} != ${total} messages read`);
  for (const id of new Set([...perChannel.keys(), ...stats.channelMessageCounts.keys()])) {
    const want = perChannel.get(id) ?? 0n;
    const got = stats.channelMessageCounts.get(id) ?? 0n;
    check(got === want, `Statistics channel_message_counts[${id}] = ${got}, read ${want}`);
  }
  check(stats.channelCount === reader.channelsById.size, `Statistics channel_count ${stats.channelCount} != ${reader.channelsById.size}`);
  check(stats.schemaCount === reader.schemasById.size, `Statistics schema_count ${stats.schemaCount} != ${reader.schemasById.size}`);
  check(stats.chunkCount === reader.chunkIndexes.length, `Statistics chunk_count ${stats.chunkCount} != ${reader.chunkIndexes.length} chunk indexes`);
  check(BigInt(recordCounts.Chunk ?? 0) === BigInt(reader.chunkIndexes.length),
    `${recordCounts.Chunk ?? 0} Chunk records but ${reader.chunkIndexes.length} chunk indexes`);
  if (total > 0n)
    check(stats.messageStartTime === minT && stats.messageEndTime === maxT,
      `Statistics message time range ${stats.messageStartTime}..${stats.messageEndTime} != ${minT}..${maxT}`);

  await fh.close();
  if (jsonlOut) fs.writeFileSync(jsonlOut, lines.length ? lines.join("\n") + "\n" : "");

  const topics = [...reader.channelsById.values()]
    .sort((x, y) => x.id - y.id)
    .map((c) => `${c.topic}=${perChannel.get(c.id) ?? 0n}`)
    .join(" ");
  console.log(
    `OK ${input}: ${total} messages, ${reader.channelsById.size} channels, ${reader.chunkIndexes.length} chunks ` +
      `(compression: ${[...chunkCompressions].join(",") || "-"}${chunksOverlap ? ", overlapping" : ""}), ` +
      `CRCs: chunk ${chunkCrcs}/${reader.chunkIndexes.length}, data ${dataCrc}, summary ${summaryCrc}; ` +
      `library "${reader.header.library}"; ${bigEndian ? `${bigEndian} big-endian CDR; ` : ""}${topics}` +
      (reencode ? `; the same bytes serialised again: ${[...reencoded].map(([k, v]) => `${k}=${v}`).join(" ")}` : ""),
  );
}

try {
  await main();
} catch (e) {
  console.error(`check_mcap.mjs: FAIL ${input}: ${e instanceof CheckError ? e.message : e.stack}`);
  process.exit(1);
}
