#!/usr/bin/env node
// Self-test of the tools against each other (npm run check): writes recordings with every
// compression and with big-endian /scan, validates them with check_mcap.mjs and compares
// its decoded JSONL with the writer's .expected.jsonl. Light: a few seconds, files in a temp dir.
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";

const here = path.dirname(new URL(import.meta.url).pathname);
const dir = fs.mkdtempSync(path.join(os.tmpdir(), "rosbag2-selftest-"));
const node = (script, ...args) =>
  execFileSync(process.execPath, [path.join(here, script), ...args], { encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] }).trim();

const cases = [
  ["none", ["--compression", "none"]],
  ["zstd", ["--compression", "zstd"]],
  ["lz4", ["--compression", "lz4"]],
  ["be-zstd-small-chunks-humble", ["--compression", "zstd", "--big-endian-scan", "--chunk-size", "4096", "--qos-style", "humble"]],
  ["be-lz4-one-chunk", ["--compression", "lz4", "--big-endian-scan", "--chunk-size", "100000000"]],
];
let passed = 0;
let failed = 0;
for (const [name, opts] of cases) {
  const mcap = path.join(dir, `${name}.mcap`);
  try {
    node("write_mcap.mjs", mcap, ...opts);
    node("check_mcap.mjs", mcap, "--jsonl", `${mcap}.jsonl`);
    node("compare_jsonl.mjs", `${mcap}.jsonl`, `${mcap}.expected.jsonl`);
    console.log(`ok   ${name}`);
    passed++;
  } catch (e) {
    console.log(`FAIL ${name}: ${(e.stderr || e.message).trim()}`);
    failed++;
  }
}
// a corrupted file must be rejected
try {
  const good = fs.readFileSync(path.join(dir, "none.mcap"));
  const bad = Buffer.from(good);
  bad[200] ^= 0xff; // inside the first (uncompressed) chunk
  fs.writeFileSync(path.join(dir, "corrupt.mcap"), bad);
  let rejected = false;
  try {
    node("check_mcap.mjs", path.join(dir, "corrupt.mcap"));
  } catch {
    rejected = true;
  }
  if (!rejected) throw new Error("check_mcap.mjs accepted a corrupted chunk");
  console.log("ok   corrupt-rejected");
  passed++;
} catch (e) {
  console.log(`FAIL corrupt-rejected: ${e.message}`);
  failed++;
}
fs.rmSync(dir, { recursive: true, force: true });
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
