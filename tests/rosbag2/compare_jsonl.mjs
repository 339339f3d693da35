#!/usr/bin/env node
// Compares two message JSONL files (format of write_mcap.mjs's .expected.jsonl and
// check_mcap.mjs --jsonl): line by line, topic, log_time_ns, type and msg fields.
//
// usage: node compare_jsonl.mjs A.jsonl B.jsonl [--topics /scan,/odom] [--tolerance 1e-9]
//
// Numbers are equal within relative tolerance (|a-b| <= tol * max(|a|,|b|)); "NaN",
// "Infinity", "-Infinity" and integer strings (bigints) also compare numerically with
// numbers; arrays must have the same length; objects the same keys. Prints the first
// difference and exits 1, or prints "same: N messages" and exits 0.
import fs from "node:fs";

const args = process.argv.slice(2);
const files = [];
let topics;
let tol = 1e-9;
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--topics" && i + 1 < args.length) topics = new Set(args[++i].split(",").filter(Boolean));
  else if (args[i] === "--tolerance" && i + 1 < args.length) tol = Number(args[++i]);
  else if (!args[i].startsWith("--")) files.push(args[i]);
  else files.length = 99;
}
if (files.length !== 2 || !(tol >= 0)) {
  console.error("usage: node compare_jsonl.mjs A.jsonl B.jsonl [--topics /scan,/odom] [--tolerance 1e-9]");
  process.exit(2);
}

function load(file) {
  const out = [];
  fs.readFileSync(file, "utf8")
    .split("\n")
    .forEach((line, i) => {
      if (line.trim() === "") return;
      let rec;
      try {
        rec = JSON.parse(line);
      } catch (e) {
        console.error(`${file}:${i + 1}: not JSON: ${e.message}`);
        process.exit(1);
      }
      if (!topics || topics.has(rec.topic)) out.push({ rec, line: i + 1 });
    });
  return out;
}

const asNumber = (v) => {
  if (typeof v === "number") return v;
  if (typeof v === "string" && /^(NaN|-?Infinity|-?\d+)$/.test(v)) return Number(v);
  return undefined;
};

function numbersEqual(x, y) {
  if (Number.isNaN(x) || Number.isNaN(y)) return Number.isNaN(x) && Number.isNaN(y);
  if (x === y) return true;
  if (!Number.isFinite(x) || !Number.isFinite(y)) return false;
  return Math.abs(x - y) <= tol * Math.max(Math.abs(x), Math.abs(y));
}

/** Returns undefined when equal, else a description of the first difference. */
function diff(a, b, path) {
  if (typeof a === "string" && typeof b === "string" && a === b) return undefined;
  const na = asNumber(a);
  const nb = asNumber(b);
  if ((typeof a === "number" || typeof b === "number") && na !== undefined && nb !== undefined) {
    // large integers (int64 as strings) compare exactly
    if (typeof a === "string" && typeof b === "string") return a === b ? undefined : `${path}: ${a} != ${b}`;
    return numbersEqual(na, nb) ? undefined : `${path}: ${JSON.stringify(a)} != ${JSON.stringify(b)}`;
  }
  if (Array.isArray(a) || Array.isArray(b)) {
    if (!Array.isArray(a) || !Array.isArray(b)) return `${path}: array vs ${Array.isArray(a) ? typeof b : typeof a}`;
    if (a.length !== b.length) return `${path}: array length ${a.length} != ${b.length}`;
    for (let i = 0; i < a.length; i++) {
      const d = diff(a[i], b[i], `${path}[${i}]`);
      if (d) return d;
    }
    return undefined;
  }
  if (a !== null && b !== null && typeof a === "object" && typeof b === "object") {
    const ka = Object.keys(a);
    const kb = Object.keys(b);
    for (const k of ka) if (!(k in b)) return `${path}.${k}: missing in B`;
    for (const k of kb) if (!(k in a)) return `${path}.${k}: missing in A`;
    for (const k of ka) {
      const d = diff(a[k], b[k], `${path}.${k}`);
      if (d) return d;
    }
    return undefined;
  }
  return a === b ? undefined : `${path}: ${JSON.stringify(a)} != ${JSON.stringify(b)}`;
}

const A = load(files[0]);
const B = load(files[1]);
const n = Math.min(A.length, B.length);
for (let i = 0; i < n; i++) {
  const a = A[i].rec;
  const b = B[i].rec;
  let d;
  if (a.topic !== b.topic) d = `topic ${JSON.stringify(a.topic)} != ${JSON.stringify(b.topic)}`;
  else if (String(a.log_time_ns) !== String(b.log_time_ns)) d = `log_time_ns ${a.log_time_ns} != ${b.log_time_ns}`;
  else if (a.type !== b.type) d = `type ${JSON.stringify(a.type)} != ${JSON.stringify(b.type)}`;
  else d = diff(a.msg, b.msg, "msg");
  if (d) {
    console.error(
      `DIFF message ${i + 1} (${files[0]}:${A[i].line}, ${files[1]}:${B[i].line}, ${a.topic} @ ${a.log_time_ns}): ${d}`,
    );
    process.exit(1);
  }
}
if (A.length !== B.length) {
  const extra = A.length > B.length ? A[n] : B[n];
  console.error(
    `DIFF message count ${A.length} (${files[0]}) != ${B.length} (${files[1]}); first unmatched: ` +
      `${extra.rec.topic} @ ${extra.rec.log_time_ns} in ${A.length > B.length ? files[0] : files[1]}`,
  );
  process.exit(1);
}
console.log(`same: ${n} messages${topics ? ` on ${[...topics].join(",")}` : ""} (tolerance ${tol})`);
