// Plain-JSON form of a decoded ROS message, shared by write_mcap.mjs (expected
// output) and check_mcap.mjs (decoded output) so both write the same JSONL format:
//   {"topic","log_time_ns" (string),"type","msg"}
// Non-finite numbers become "NaN", "Infinity", "-Infinity"; bigints become decimal
// strings; typed arrays become arrays; object keys keep field order.

export function toPlain(value) {
  if (typeof value === "number") {
    if (Number.isNaN(value)) return "NaN";
    if (value === Infinity) return "Infinity";
    if (value === -Infinity) return "-Infinity";
    return value;
  }
  if (typeof value === "bigint") return value.toString();
  if (value === null || value === undefined) return null;
  if (ArrayBuffer.isView(value)) return Array.from(value, toPlain);
  if (Array.isArray(value)) return value.map(toPlain);
  if (typeof value === "object") {
    const out = {};
    for (const [k, v] of Object.entries(value)) out[k] = toPlain(v);
    return out;
  }
  return value; // string, boolean
}

export function jsonlLine(topic, logTimeNs, type, msg) {
  return JSON.stringify({ topic, log_time_ns: BigInt(logTimeNs).toString(), type, msg: toPlain(msg) });
}
