// WiROS-like ROS 2 recordings written with independent code, for the rosbag2 tests of
// csi-import: MCAP by npm's @mcap/core, CDR by @foxglove/rosmsg2-serialization from ros2msg
// definition text (parsed by @foxglove/rosmsg), zstd by @foxglove/wasm-zstd and lz4 frames by
// Debian's lz4 program. Nothing of this project's code is used.
//
//   node ros2_bag_writer.mjs mcap DIR          DIR/bag_0.mcap (summary; zstd, lz4 and plain
//                                              chunks), DIR/bag_1.mcap (no summary),
//                                              DIR/metadata.yaml, DIR/expected.txt
//   node ros2_bag_writer.mjs sqlite-input DIR  DIR/messages.json (topics, CDR messages and
//                                              definitions for ros2_sqlite_bag.py) and
//                                              DIR/expected.txt
//   node ros2_bag_writer.mjs decode DEF BIN    reads BIN (CDR) with the definition in DEF and
//                                              prints it as an expected.txt frame, then
//                                              "reencoded <hex>" (the message written back)
//
// expected.txt, one block per rf_msgs/msg/Wifi a reader must import (the others are described
// in comments at the top):
//   frame RX_ID SEC NANOSEC FRAME_ID TXMAC CHAN N_SUB N_ROWS N_COLS BW MCS RSSI FC SEQ_NUM MSG_ID AP_ID
//   re V...   (csi_real)
//   im V...   (csi_imag)
// SEC NANOSEC are the time the reader must give the frame (the bag's time where the stamp is 0).
// Requires NPM_TOOLS (the folder scripts/install-deps.sh installs the packages into).
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";

const npmTools = process.env.NPM_TOOLS;
if (!npmTools) throw new Error("set NPM_TOOLS to the npm-tools folder");
const require = createRequire(path.join(npmTools, "node_modules", "index.js"));
const { McapWriter } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageWriter, MessageReader } = require("@foxglove/rosmsg2-serialization");
const zstd = require("@foxglove/wasm-zstd");

const SEPARATOR = "=".repeat(80);

// rf_msgs/msg/Wifi as rosbag2 stores it from WiROS's .msg file: the file's text (comments and
// all, nested types spelled as in the file), then each dependency after a separator.
function wifiMsgText(headerType, csiType) {
  return `# CSI of one overheard frame (WiROS rf_msgs). The CSI matrix is n_sub x n_rows x n_cols.
${headerType} header

uint8 ap_id     # receiving access point
uint8[] txmac   # transmitter address, 6 bytes
uint8 chan      # channel number
uint32 n_sub    # subcarriers
uint8 n_rows    # receive antennas
uint8 n_cols    # transmit streams
uint8 bw        # MHz
uint8 mcs
int32 rssi
uint32 fc       # frame control
uint32 seq_num  # sequence control
${csiType}[] csi_real  # column-major, subcarriers fastest
${csiType}[] csi_imag
string rx_id    # receiver
uint32 msg_id
`;
}
function dependencies(timeType) {
  return `${SEPARATOR}
MSG: std_msgs/msg/Header
# Standard metadata for stamped data
${timeType} stamp
string frame_id
${SEPARATOR}
MSG: builtin_interfaces/msg/Time
# time since the epoch
int32 sec
uint32 nanosec
`;
}
// What rosbag2 writes (its .msg text is "std_msgs/Header header"), and the spelling
// @foxglove/rosmsg can resolve, which the serializer is built from.
const WIFI_AS_ROSBAG2 = wifiMsgText("std_msgs/Header", "float64") + dependencies("builtin_interfaces/Time");
const WIFI_PARSEABLE =
  wifiMsgText("std_msgs/msg/Header", "float64") + dependencies("builtin_interfaces/msg/Time");
// An older rf_msgs with float32 CSI under the same name: a reader must refuse it.
const WIFI_FLOAT32 =
  wifiMsgText("std_msgs/msg/Header", "float32") + dependencies("builtin_interfaces/msg/Time");
const STRING_DEF = "string data\n";

const wifiWriter = new MessageWriter(parse(WIFI_PARSEABLE, { ros2: true }));
const float32Writer = new MessageWriter(parse(WIFI_FLOAT32, { ros2: true }));
const stringWriter = new MessageWriter(parse(STRING_DEF, { ros2: true }));

const RECEIVERS = [
  { rxId: "192.168.50.1", chan: 155, bw: 80, nSub: 256, nRows: 4, nCols: 2, mac: [2, 0, 0, 0, 10, 1] },
  { rxId: "192.168.50.2", chan: 36, bw: 20, nSub: 64, nRows: 4, nCols: 1, mac: [2, 0, 0, 0, 10, 2] },
];

// A message's values are exact in float32 (the observation's precision) and differ by
// receiver, message, stream, antenna and subcarrier. Stream 1 / antenna 3 of the first receiver
// is all zeros (absent).
function wifiMessage(rxIndex, msgId, stampSec, stampNsec) {
  const r = RECEIVERS[rxIndex];
  const n = r.nSub * r.nRows * r.nCols;
  const re = new Float64Array(n);
  const im = new Float64Array(n);
  for (let tx = 0; tx < r.nCols; tx++)
    for (let rx = 0; rx < r.nRows; rx++) {
      if (rxIndex === 0 && tx === 1 && rx === 3) continue;
      for (let k = 0; k < r.nSub; k++) {
        const i = k + r.nSub * (rx + r.nRows * tx);
        re[i] = ((msgId * 37 + tx * 11 + rx * 5 + k) % 401) * 0.25 - 50;
        im[i] = -(((msgId * 13 + tx * 7 + rx * 3 + 2 * k) % 307) * 0.125) + 17.5;
      }
    }
  return {
    header: { stamp: { sec: stampSec, nanosec: stampNsec }, frame_id: `wifi_${rxIndex}` },
    ap_id: rxIndex + 1,
    txmac: Uint8Array.from(r.mac),
    chan: r.chan,
    n_sub: r.nSub,
    n_rows: r.nRows,
    n_cols: r.nCols,
    bw: r.bw,
    mcs: 3 + rxIndex,
    rssi: -40 - (msgId % 50),
    fc: 0x88,
    seq_num: ((100 + msgId) << 4) | (msgId % 3),
    csi_real: re,
    csi_imag: im,
    rx_id: r.rxId,
    msg_id: msgId,
  };
}

function frameText(m, sec, nanosec) {
  const mac = Array.from(m.txmac, (b) => b.toString(16).padStart(2, "0")).join(":");
  return (
    [
      "frame", m.rx_id, sec, nanosec, m.header.frame_id, mac, m.chan, m.n_sub, m.n_rows, m.n_cols,
      m.bw, m.mcs, m.rssi, m.fc, m.seq_num, m.msg_id, m.ap_id,
    ].join(" ") +
    "\nre " + Array.from(m.csi_real).join(" ") +
    "\nim " + Array.from(m.csi_imag).join(" ") + "\n"
  );
}

// The messages of one bag file, in log-time order: [topic, kind, message, logTimeNs, expected?]
// kinds: wifi, float32 (other definition), string (another type).
function messagesOf(fileIndex) {
  const list = [];
  const base = 1700000000n + BigInt(fileIndex) * 100n;
  let t = 0;
  const at = () => (base + BigInt(t)) * 1000000000n + BigInt(1000 * t++);
  for (let i = 0; i < 6; i++) {
    const msgId = fileIndex * 100 + i;
    const logTime = at();
    const sec = Number(logTime / 1000000000n);
    const nsec = Number(logTime % 1000000000n) + 17;
    // Receiver 0 on /csi, receiver 1 on /csi and on /robot2/wifi/csi.
    const rx = i % 2;
    const topic = rx === 1 && i >= 3 ? "/robot2/wifi/csi" : "/csi";
    // One message stamped 0: the reader takes the bag's time.
    const zeroStamp = i === 4;
    const m = wifiMessage(rx, msgId, zeroStamp ? 0 : sec, zeroStamp ? 0 : nsec);
    list.push({
      topic, kind: "wifi", message: m, logTime,
      expected: zeroStamp
        ? frameText(m, Number(logTime / 1000000000n), Number(logTime % 1000000000n))
        : frameText(m, sec, nsec),
    });
    if (i === 2) list.push({ topic: "/chatter", kind: "string", message: { data: `hello ${i}` }, logTime: at() });
  }
  // One whose arrays disagree with n_sub x n_rows x n_cols.
  const bad = wifiMessage(1, fileIndex * 100 + 50, 1700000500, 0);
  bad.csi_real = bad.csi_real.slice(1);
  list.push({ topic: "/csi", kind: "wifi", message: bad, logTime: at() });
  // One of another definition.
  const old = wifiMessage(0, fileIndex * 100 + 60, 1700000600, 0);
  old.csi_real = Float32Array.from(old.csi_real);
  old.csi_imag = Float32Array.from(old.csi_imag);
  list.push({ topic: "/csi_v0", kind: "float32", message: old, logTime: at() });
  list.push({ topic: "/chatter", kind: "string", message: { data: "bye" }, logTime: at() });
  return list;
}

const serializers = { wifi: wifiWriter, float32: float32Writer, string: stringWriter };

function lz4Frame(bytes) {
  return new Uint8Array(execFileSync("lz4", ["-q", "-c", "-z"], { input: Buffer.from(bytes) }));
}

class MemoryWritable {
  constructor() {
    this.parts = [];
    this.size = 0n;
  }
  async write(buffer) {
    this.parts.push(Buffer.from(buffer));
    this.size += BigInt(buffer.byteLength);
  }
  position() {
    return this.size;
  }
}

const QOS = "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 2\n";

async function writeMcap(file, fileIndex, withSummary, schemaText) {
  const out = new MemoryWritable();
  const compressions = ["zstd", "lz4", ""];
  let chunkCount = 0;
  const writer = new McapWriter({
    writable: out,
    chunkSize: 40000, // several chunks, each compression at least once
    useStatistics: withSummary,
    useSummaryOffsets: withSummary,
    useChunkIndex: withSummary,
    useMessageIndex: withSummary,
    repeatSchemas: withSummary,
    repeatChannels: withSummary,
    useAttachmentIndex: withSummary,
    useMetadataIndex: withSummary,
    compressChunk: (data) => {
      const compression = compressions[chunkCount++ % compressions.length];
      if (compression === "zstd") return { compression, compressedData: zstd.compress(data, 3) };
      if (compression === "lz4") return { compression, compressedData: lz4Frame(data) };
      return { compression: "", compressedData: data };
    },
  });
  await writer.start({ profile: "ros2", library: "ros2_bag_writer.mjs" });
  const enc = new TextEncoder();
  const schemas = {
    wifi: await writer.registerSchema({ name: "rf_msgs/msg/Wifi", encoding: "ros2msg", data: enc.encode(schemaText) }),
    float32: await writer.registerSchema({ name: "rf_msgs/msg/Wifi", encoding: "ros2msg", data: enc.encode(WIFI_FLOAT32) }),
    string: await writer.registerSchema({ name: "std_msgs/msg/String", encoding: "ros2msg", data: enc.encode(STRING_DEF) }),
  };
  const channels = new Map();
  let sequence = 0;
  let expected = "";
  for (const m of messagesOf(fileIndex)) {
    const key = `${m.topic} ${m.kind}`;
    if (!channels.has(key))
      channels.set(
        key,
        await writer.registerChannel({
          schemaId: schemas[m.kind], topic: m.topic, messageEncoding: "cdr",
          metadata: new Map([["offered_qos_profiles", QOS]]),
        }),
      );
    await writer.addMessage({
      channelId: channels.get(key), sequence: sequence++, logTime: m.logTime, publishTime: m.logTime,
      data: serializers[m.kind].writeMessage(m.message),
    });
    if (m.expected) expected += m.expected;
  }
  await writer.end();
  fs.writeFileSync(file, Buffer.concat(out.parts));
  return { expected, chunks: chunkCount };
}

async function mcapBag(dir) {
  await zstd.isLoaded;
  fs.mkdirSync(dir, { recursive: true });
  const a = await writeMcap(path.join(dir, "bag_0.mcap"), 0, true, WIFI_AS_ROSBAG2);
  const b = await writeMcap(path.join(dir, "bag_1.mcap"), 1, false, WIFI_PARSEABLE);
  if (a.chunks < 3 || b.chunks < 3) throw new Error("expected at least 3 chunks per file");
  fs.writeFileSync(
    path.join(dir, "metadata.yaml"),
    `rosbag2_bagfile_information:
  version: 8
  storage_identifier: mcap
  relative_file_paths:
    - bag_0.mcap
    - bag_1.mcap
  compression_format: ""
  compression_mode: ""
`,
  );
  fs.writeFileSync(
    path.join(dir, "expected.txt"),
    `# bag_0.mcap: 6 rf_msgs/msg/Wifi imported, 1 whose sizes disagree, 1 of another definition, 2 std_msgs/msg/String; chunks ${a.chunks}\n` +
      `# bag_1.mcap: the same (no summary); chunks ${b.chunks}\n` +
      a.expected + b.expected,
  );
}

async function sqliteInput(dir) {
  fs.mkdirSync(dir, { recursive: true });
  const topics = [];
  const topicIds = new Map();
  const messages = [];
  let expected = "# bag_0.db3: 6 rf_msgs/msg/Wifi imported, 1 whose sizes disagree, 1 of another definition (float32 CSI: malformed as CDR), 2 std_msgs/msg/String\n";
  for (const m of messagesOf(0)) {
    const type = m.kind === "string" ? "std_msgs/msg/String" : "rf_msgs/msg/Wifi";
    if (!topicIds.has(m.topic)) {
      topicIds.set(m.topic, topics.length + 1);
      topics.push({ id: topics.length + 1, name: m.topic, type, serialization_format: "cdr", offered_qos_profiles: QOS });
    }
    const data = serializers[m.kind].writeMessage(m.message);
    messages.push({ topic_id: topicIds.get(m.topic), timestamp: m.logTime.toString(), data: Buffer.from(data).toString("base64") });
    if (m.expected) expected += m.expected;
  }
  // Stored out of time order: a reader must sort by timestamp as rosbag2 does.
  messages.reverse();
  // The definitions an Iron bag keeps (message_definitions), and an older rf_msgs's.
  const definitions = { "rf_msgs/msg/Wifi": WIFI_AS_ROSBAG2, "std_msgs/msg/String": STRING_DEF };
  fs.writeFileSync(
    path.join(dir, "messages.json"),
    JSON.stringify({ topics, messages, definitions, float32_wifi: WIFI_FLOAT32 }),
  );
  fs.writeFileSync(path.join(dir, "expected.txt"), expected);
}

function decode(defFile, binFile) {
  const definition = parse(fs.readFileSync(defFile, "utf8"), { ros2: true });
  const reader = new MessageReader(definition);
  const bytes = fs.readFileSync(binFile);
  const m = reader.readMessage(bytes);
  if (reader.lastReadHadTrailingBytes()) throw new Error("trailing bytes after the message");
  process.stdout.write(frameText(m, m.header.stamp.sec, m.header.stamp.nanosec));
  const again = new MessageWriter(definition).writeMessage(m);
  process.stdout.write(`reencoded ${Buffer.from(again).toString("hex")}\n`);
}

const [mode, ...args] = process.argv.slice(2);
if (mode === "mcap") await mcapBag(args[0]);
else if (mode === "sqlite-input") await sqliteInput(args[0]);
else if (mode === "decode") decode(args[0], args[1]);
else {
  console.error("usage: ros2_bag_writer.mjs mcap DIR | sqlite-input DIR | decode DEF BIN");
  process.exit(2);
}
