// Reads an MCAP file with independent code (npm's @mcap/core, @foxglove/rosmsg,
// @foxglove/rosmsg2-serialization, @foxglove/wasm-zstd / wasm-lz4, @foxglove/crc) and compares
// it with what it must hold (a JSON file the C++ test writes from the data the file came from).
//
//   NODE_PATH=<npm-tools>/node_modules node mcap_check.mjs FILE.mcap EXPECTED.json
//
// EXPECTED: { profile, compression, schemas: { name: ["field:type", ...] }, channels: [{ topic,
// schema, messageEncoding, metadataKeys }], messages: [{ topic, logTime, message, partial? }],
// tolerance?, timeToleranceNs? } (tolerances for values taken from rounded text output; else
// numbers must be equal, float32 fields to the nearest float).
// Checks: the header profile; both readers (indexed through the summary and message indexes,
// and streaming front to back, chunk CRCs validated); the data-section and summary CRCs
// recomputed over the file's bytes; statistics; each schema parsed as ros2msg with its fields;
// channels; every message decoded with its schema and compared field by field (all fields
// unless `partial`), log time = publish time = header stamp where the message has one; per
// channel, sequence numbers 0, 1, ... and log times never decreasing. Prints every difference and
// exits 1, or prints a one-line summary and exits 0.
import { createRequire } from "node:module";
import { readFileSync } from "node:fs";
import path from "node:path";

const require = createRequire(path.join(process.env.NODE_PATH ?? ".", "x.js"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { parse: parseMessageDefinition } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const { crc32 } = require("@foxglove/crc");
const zstd = require("@foxglove/wasm-zstd");
const lz4 = require("@foxglove/wasm-lz4");

const [file, expectedFile] = process.argv.slice(2);
const bytes = new Uint8Array(readFileSync(file));
const expected = JSON.parse(readFileSync(expectedFile, "utf8"));
const tolerance = expected.tolerance ?? 0;
const timeToleranceNs = BigInt(expected.timeToleranceNs ?? 0);
const closeTimes = (a, b) => (a > b ? a - b : b - a) <= timeToleranceNs;
const errors = [];
const fail = (what) => {
  if (errors.length < 40) errors.push(what);
  else if (errors.length === 40) errors.push("... more differences left out");
};

await zstd.isLoaded;
await lz4.isLoaded;
const decompressHandlers = {
  zstd: (buf, size) => zstd.decompress(buf, Number(size)),
  lz4: (buf, size) => lz4(buf, Number(size)),
};

// --- indexed reader ---
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
if (indexed.header.profile !== expected.profile)
  fail(`header profile '${indexed.header.profile}', expected '${expected.profile}'`);

// CRCs the reader does not check itself: the data section (file start to the Data End record)
// and the summary (summary start up to the footer's CRC field).
const dataEnd = Number(indexed.dataEndOffset);
if (indexed.dataSectionCrc !== crc32(bytes.subarray(0, dataEnd)))
  fail(`data section CRC ${indexed.dataSectionCrc} != ${crc32(bytes.subarray(0, dataEnd))}`);
const summaryStart = Number(indexed.footer.summaryStart);
const summaryCrc = crc32(bytes.subarray(summaryStart, bytes.length - 8 - 4));
if (summaryStart === 0) fail("no summary section");
if (indexed.footer.summaryCrc !== summaryCrc)
  fail(`summary CRC ${indexed.footer.summaryCrc} != ${summaryCrc}`);
if (indexed.summaryOffsetsByOpcode.size === 0) fail("no summary offsets");
for (const ci of indexed.chunkIndexes)
  if (ci.compression !== expected.compression)
    fail(`chunk compression '${ci.compression}', expected '${expected.compression}'`);
if (indexed.chunkIndexes.length === 0) fail("no chunk index");

// --- schemas and channels ---
const fieldList = (defs) =>
  defs.definitions
    .filter((d) => d.isConstant !== true)
    .map((d) => {
      const base = d.type.split("/").pop();
      const arr = d.isArray === true ? (d.arrayLength != undefined ? `[${d.arrayLength}]` : "[]") : "";
      return `${d.name}:${base}${arr}`;
    });
const readers = new Map(); // schema id -> { reader, hasHeader }
for (const [id, schema] of indexed.schemasById) {
  if (schema.encoding !== "ros2msg") fail(`schema ${schema.name}: encoding '${schema.encoding}'`);
  let defs;
  try {
    defs = parseMessageDefinition(new TextDecoder().decode(schema.data), { ros2: true });
  } catch (e) {
    fail(`schema ${schema.name} does not parse: ${e.message}`);
    continue;
  }
  const want = expected.schemas[schema.name];
  if (!want) fail(`unexpected schema ${schema.name}`);
  else if (JSON.stringify(fieldList(defs[0])) !== JSON.stringify(want))
    fail(`schema ${schema.name} fields ${JSON.stringify(fieldList(defs[0]))}, expected ${JSON.stringify(want)}`);
  readers.set(id, {
    reader: new MessageReader(defs),
    hasHeader: defs[0].definitions.some((d) => d.name === "header"),
  });
}
for (const name of Object.keys(expected.schemas))
  if (![...indexed.schemasById.values()].some((s) => s.name === name)) fail(`no schema ${name}`);
const channelByTopic = new Map();
for (const ch of indexed.channelsById.values()) channelByTopic.set(ch.topic, ch);
if (indexed.channelsById.size !== expected.channels.length)
  fail(`${indexed.channelsById.size} channels, expected ${expected.channels.length}`);
for (const want of expected.channels) {
  const ch = channelByTopic.get(want.topic);
  if (!ch) {
    fail(`no channel ${want.topic}`);
    continue;
  }
  const schema = indexed.schemasById.get(ch.schemaId);
  if (schema?.name !== want.schema) fail(`${want.topic}: schema ${schema?.name}, expected ${want.schema}`);
  if (ch.messageEncoding !== want.messageEncoding)
    fail(`${want.topic}: message encoding '${ch.messageEncoding}'`);
  const keys = [...ch.metadata.keys()].sort();
  if (JSON.stringify(keys) !== JSON.stringify([...want.metadataKeys].sort()))
    fail(`${want.topic}: metadata keys ${JSON.stringify(keys)}`);
  for (const k of keys) if (ch.metadata.get(k).length === 0) fail(`${want.topic}: empty metadata ${k}`);
}

// --- statistics ---
const st = indexed.statistics;
if (!st) fail("no statistics");
else {
  if (Number(st.messageCount) !== expected.messages.length)
    fail(`statistics: ${st.messageCount} messages, expected ${expected.messages.length}`);
  if (st.chunkCount !== indexed.chunkIndexes.length) fail(`statistics: chunk count ${st.chunkCount}`);
  if (st.channelCount !== indexed.channelsById.size) fail(`statistics: channel count ${st.channelCount}`);
  for (const [id, ch] of indexed.channelsById) {
    const n = expected.messages.filter((m) => m.topic === ch.topic).length;
    if (Number(st.channelMessageCounts.get(id) ?? -1) !== n)
      fail(`statistics: ${ch.topic} count ${st.channelMessageCounts.get(id)}, expected ${n}`);
  }
  if (expected.messages.length > 0) {
    const times = expected.messages.map((m) => BigInt(m.logTime));
    const min = times.reduce((a, b) => (b < a ? b : a));
    const max = times.reduce((a, b) => (b > a ? b : a));
    if (!closeTimes(st.messageStartTime, min) || !closeTimes(st.messageEndTime, max))
      fail(`statistics: time range ${st.messageStartTime}..${st.messageEndTime}, expected ${min}..${max}`);
  }
}

// --- messages ---
const plain = (v) => {
  if (typeof v === "bigint") return v.toString();
  if (ArrayBuffer.isView(v)) return Array.from(v, plain);
  if (Array.isArray(v)) return v.map(plain);
  if (v && typeof v === "object") {
    const o = {};
    for (const [k, x] of Object.entries(v)) o[k] = plain(x);
    return o;
  }
  return v;
};
const compare = (actual, want, where, partial) => {
  if (Array.isArray(want)) {
    if (!Array.isArray(actual)) return fail(`${where}: not an array`);
    if (actual.length !== want.length)
      return fail(`${where}: ${actual.length} elements, expected ${want.length}`);
    want.forEach((w, i) => compare(actual[i], w, `${where}[${i}]`, partial));
  } else if (want && typeof want === "object") {
    if (!actual || typeof actual !== "object") return fail(`${where}: not an object`);
    const wk = Object.keys(want).sort();
    const ak = Object.keys(actual).sort();
    if (!partial && JSON.stringify(wk) !== JSON.stringify(ak))
      fail(`${where}: fields ${JSON.stringify(ak)}, expected ${JSON.stringify(wk)}`);
    for (const k of wk) {
      if (!(k in actual)) fail(`${where}.${k}: missing`);
      else compare(actual[k], want[k], `${where}.${k}`, partial);
    }
  } else if (typeof want === "number" && typeof actual === "number") {
    // float32 fields hold the nearest float of the expected value.
    if (actual !== want && actual !== Math.fround(want) && !(Math.abs(actual - want) <= tolerance))
      fail(`${where}: ${actual}, expected ${want}`);
  } else if (actual !== want) fail(`${where}: ${JSON.stringify(actual)}, expected ${JSON.stringify(want)}`);
};

const decodeAll = (records, label) => {
  const out = [];
  for (const rec of records) {
    const ch = channels.get(rec.channelId);
    const r = readers.get(ch?.schemaId);
    if (!ch || !r) {
      fail(`${label}: message on unknown channel ${rec.channelId}`);
      continue;
    }
    let msg;
    try {
      msg = plain(r.reader.readMessage(rec.data));
    } catch (e) {
      fail(`${label}: ${ch.topic} #${rec.sequence}: does not decode: ${e.message}`);
      continue;
    }
    if (r.reader.lastReadHadTrailingBytes())
      fail(`${label}: ${ch.topic} #${rec.sequence}: bytes left after decoding`);
    if (rec.publishTime !== rec.logTime) fail(`${label}: ${ch.topic}: publish time != log time`);
    if (r.hasHeader) {
      const stamp = BigInt(msg.header.stamp.sec) * 1000000000n + BigInt(msg.header.stamp.nanosec);
      if (stamp !== rec.logTime)
        fail(`${label}: ${ch.topic} #${rec.sequence}: log time ${rec.logTime} != header stamp ${stamp}`);
    }
    out.push({ topic: ch.topic, sequence: rec.sequence, logTime: rec.logTime.toString(), message: msg });
  }
  return out;
};
const channels = indexed.channelsById;
const checkAgainstExpected = (got, want, label) => {
  if (got.length !== want.length) fail(`${label}: ${got.length} messages, expected ${want.length}`);
  const n = Math.min(got.length, want.length);
  for (let i = 0; i < n; ++i) {
    const g = got[i];
    const w = want[i];
    const where = `${label} message ${i} (${w.topic})`;
    if (g.topic !== w.topic) {
      fail(`${where}: on ${g.topic}`);
      continue;
    }
    if (!closeTimes(BigInt(g.logTime), BigInt(w.logTime)))
      fail(`${where}: log time ${g.logTime}, expected ${w.logTime}`);
    compare(g.message, w.message, where, w.partial === true);
  }
};
const checkSequences = (got, label) => {
  const next = new Map();
  const last = new Map();
  for (const g of got) {
    const n = next.get(g.topic) ?? 0;
    if (g.sequence !== n) fail(`${label}: ${g.topic} sequence ${g.sequence}, expected ${n}`);
    next.set(g.topic, n + 1);
    if (last.has(g.topic) && BigInt(g.logTime) < last.get(g.topic))
      fail(`${label}: ${g.topic}: log times go back at sequence ${g.sequence}`);
    last.set(g.topic, BigInt(g.logTime));
  }
};

const indexedRecords = [];
for await (const m of indexed.readMessages({ validateCrcs: true })) indexedRecords.push(m);
const fromIndex = decodeAll(indexedRecords, "indexed");
// The indexed reader returns messages by log time.
const byTime = expected.messages
  .map((m, i) => ({ m, i }))
  .sort((a, b) => (BigInt(a.m.logTime) < BigInt(b.m.logTime) ? -1 : BigInt(a.m.logTime) > BigInt(b.m.logTime) ? 1 : a.i - b.i))
  .map((x) => x.m);
checkAgainstExpected(fromIndex, byTime, "indexed");

const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
const streamRecords = [];
let sawFooter = false;
const streamSchemas = new Set();
const streamChannels = new Set();
for (let rec; (rec = stream.nextRecord()); ) {
  if (rec.type === "Message") {
    if (!streamChannels.has(rec.channelId)) fail(`stream: message before its channel ${rec.channelId}`);
    streamRecords.push(rec);
  } else if (rec.type === "Schema") streamSchemas.add(rec.id);
  else if (rec.type === "Channel") {
    if (!streamSchemas.has(rec.schemaId)) fail(`stream: channel ${rec.topic} before its schema`);
    streamChannels.add(rec.id);
  } else if (rec.type === "Footer") sawFooter = true;
}
if (!stream.done()) fail("stream: the reader did not reach the end");
if (!sawFooter) fail("stream: no footer");
const fromStream = decodeAll(streamRecords, "stream");
checkAgainstExpected(fromStream, expected.messages, "stream");
checkSequences(fromStream, "stream");

if (errors.length > 0) {
  for (const e of errors) console.log(`MISMATCH ${e}`);
  process.exit(1);
}
console.log(
  `OK ${file}: ${fromStream.length} messages on ${indexed.channelsById.size} channels in ` +
    `${indexed.chunkIndexes.length} ${expected.compression || "uncompressed"} chunks, equal in both readers`,
);
