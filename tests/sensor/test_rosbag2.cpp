/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Issue 55: WiROS's ROS 2 recordings in. The CDR messages here; the bags (MCAP, SQLite) written
// by independent code (tests/sensor/ros2_bag_writer.mjs with npm's @mcap/core and
// @foxglove/rosmsg2-serialization, Python's sqlite3) and read by csi-import.
#include <gtest/gtest.h>
#include <malloc.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/Ros2Messages.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
ros1::WifiMessage sampleWifi()
{
    ros1::WifiMessage m;
    m.header.stampSec = 1700000123, m.header.stampNsec = 456789012;
    m.header.frameId = "wifi";
    m.apId = 3, m.txmac = {2, 0, 0, 0, 0x0a, 1}, m.chan = 155, m.nSub = 256;
    m.nRows = 4, m.nCols = 1, m.bw = 80, m.mcs = 7, m.rssi = -47, m.fc = 0x88;
    m.seqNum = (1234 << 4) | 2;
    for (size_t i = 0; i < 256 * 4; ++i)
        m.csiReal.push_back(0.5 * double(i)), m.csiImag.push_back(-0.25 * double(i));
    m.rxId = "192.168.50.1", m.msgId = 77;
    return m;
}
}  // namespace

TEST(Ros2Messages, WifiCdrRoundTripAndLayout)
{
    const auto m = sampleWifi();
    const auto bytes = ros2::serializeCdr(m);
    ASSERT_GE(bytes.size(), 16u);
    // CDR little-endian encapsulation, then stamp.sec (int32), stamp.nanosec, frame_id.
    EXPECT_EQ(
        std::vector<uint8_t>(bytes.begin(), bytes.begin() + 4), (std::vector<uint8_t>{0, 1, 0, 0}));
    uint32_t sec = 0, nsec = 0, frameLen = 0;
    std::memcpy(&sec, bytes.data() + 4, 4), std::memcpy(&nsec, bytes.data() + 8, 4);
    std::memcpy(&frameLen, bytes.data() + 12, 4);
    EXPECT_EQ(sec, 1700000123u);
    EXPECT_EQ(nsec, 456789012u);
    EXPECT_EQ(frameLen, 5u);  // "wifi" and its NUL
    // Alignment padding is zero, whatever the memory held before (the same message always
    // gives the same bytes): before txmac's count (after ap_id) and before n_sub (after chan).
    // glibc's M_PERTURB fills every new allocation with garbage meanwhile.
    mallopt(M_PERTURB, 0xAB);
    const auto perturbed = ros2::serializeCdr(m);
    mallopt(M_PERTURB, 0);
    EXPECT_EQ(perturbed, bytes);
    for (size_t pad : {22u, 23u, 35u}) EXPECT_EQ(perturbed[pad], 0) << "padding byte " << pad;
    for (size_t pad : {22u, 23u, 35u}) EXPECT_EQ(bytes[pad], 0) << "padding byte " << pad;
    ros1::WifiMessage back;
    std::string why;
    ASSERT_TRUE(ros2::deserializeCdr(bytes.data(), bytes.size(), back, why)) << why;
    EXPECT_EQ(back.header.stampSec, m.header.stampSec);
    EXPECT_EQ(back.header.stampNsec, m.header.stampNsec);
    EXPECT_EQ(back.header.frameId, "wifi");
    EXPECT_EQ(back.apId, m.apId);
    EXPECT_EQ(back.txmac, m.txmac);
    EXPECT_EQ(back.chan, m.chan);
    EXPECT_EQ(back.nSub, m.nSub);
    EXPECT_EQ(back.nRows, m.nRows);
    EXPECT_EQ(back.nCols, m.nCols);
    EXPECT_EQ(back.bw, m.bw);
    EXPECT_EQ(back.mcs, m.mcs);
    EXPECT_EQ(back.rssi, m.rssi);
    EXPECT_EQ(back.fc, m.fc);
    EXPECT_EQ(back.seqNum, m.seqNum);
    EXPECT_EQ(back.csiReal, m.csiReal);
    EXPECT_EQ(back.csiImag, m.csiImag);
    EXPECT_EQ(back.rxId, "192.168.50.1");
    EXPECT_EQ(back.msgId, m.msgId);
    // Cut short, a huge count, surplus bytes, XCDR2: refused with what and where.
    EXPECT_FALSE(ros2::deserializeCdr(bytes.data(), bytes.size() - 3, back, why));
    EXPECT_NE(why.find("msg_id"), std::string::npos) << why;
    auto longer = bytes;
    longer.insert(longer.end(), 8, 0);
    EXPECT_FALSE(ros2::deserializeCdr(longer.data(), longer.size(), back, why));
    EXPECT_NE(why.find("left over"), std::string::npos) << why;
    auto padded = bytes;
    padded.insert(padded.end(), 3, 0);  // alignment padding some writers add
    EXPECT_TRUE(ros2::deserializeCdr(padded.data(), padded.size(), back, why)) << why;
    auto xcdr2 = bytes;
    xcdr2[1] = 7;
    EXPECT_FALSE(ros2::deserializeCdr(xcdr2.data(), xcdr2.size(), back, why));
    EXPECT_NE(why.find("encapsulation"), std::string::npos) << why;
    auto hugeCount = bytes;
    const uint32_t huge = 0x7fffffff;
    std::memcpy(hugeCount.data() + 4 + 4 + 4 + 4 + 8, &huge, 4);  // txmac's count after ap_id
    EXPECT_FALSE(ros2::deserializeCdr(hugeCount.data(), hugeCount.size(), back, why));
    EXPECT_NE(why.find("txmac"), std::string::npos) << why;
    // The message as an observation: the ROS 1 reader's meanings.
    CObservationWiFiCSI obs;
    ASSERT_TRUE(ros2::deserializeCdr(bytes.data(), bytes.size(), back, why)) << why;
    ASSERT_TRUE(ros1::toObservation(back, obs, why)) << why;
    EXPECT_EQ(obs.sequenceNumber, 1234);
    EXPECT_EQ(obs.fragmentNumber, 2);
    EXPECT_EQ(obs.at(0, 2, 5), CObservationWiFiCSI::Complex(0.5f * 517, -0.25f * 517));
}

TEST(Ros2Messages, BearingCdrRoundTrip)
{
    ros1::BearingMessage m;
    m.header.stampSec = 5, m.header.stampNsec = 6, m.header.frameId = "base_link";
    m.apId = 1, m.txmac = {1, 2, 3, 4, 5, 6}, m.nTx = 1, m.nRx = 4, m.seq = 99;
    m.rssi = {-40, -41}, m.aoa = {0.25, -1.5};
    const auto bytes = ros2::serializeCdr(m);
    ros1::BearingMessage back;
    std::string why;
    ASSERT_TRUE(ros2::deserializeCdr(bytes.data(), bytes.size(), back, why)) << why;
    EXPECT_EQ(back.header.stampSec, 5u);
    EXPECT_EQ(back.header.stampNsec, 6u);
    EXPECT_EQ(back.header.frameId, "base_link");
    EXPECT_EQ(back.apId, 1);
    EXPECT_EQ(back.txmac, m.txmac);
    EXPECT_EQ(back.nTx, 1);
    EXPECT_EQ(back.nRx, 4);
    EXPECT_EQ(back.seq, 99u);
    EXPECT_EQ(back.rssi, m.rssi);
    EXPECT_EQ(back.aoa, m.aoa);
    // A Wifi is not a Bearing.
    const auto wifi = ros2::serializeCdr(sampleWifi());
    EXPECT_FALSE(ros2::deserializeCdr(wifi.data(), wifi.size(), back, why));
}

TEST(Ros2Messages, DefinitionsAsRosbag2WritesThem)
{
    EXPECT_EQ(ros2::wifiType().name, "rf_msgs/msg/Wifi");
    EXPECT_EQ(ros2::bearingType().name, "rf_msgs/msg/Bearing");
    const std::string& d = ros2::wifiType().definition;
    EXPECT_EQ(d.rfind("std_msgs/msg/Header header\n", 0), 0u);
    EXPECT_NE(
        d.find(
            "\n================================================================================\n"
            "MSG: std_msgs/msg/Header\n"),
        std::string::npos);
    EXPECT_NE(
        d.find("MSG: builtin_interfaces/msg/Time\nint32 sec\nuint32 nanosec\n"), std::string::npos);
    std::string why;
    EXPECT_TRUE(ros2::sameDefinition(ros2::wifiType(), d, why)) << why;
    // Comments, spacing, constants, defaults and type spellings do not matter...
    const std::string commented =
        "# CSI of one frame\nHeader  header # stamp\nuint8 AP_UNKNOWN=255\nuint8 ap_id\n"
        "uint8[] txmac\nuint8 chan\nuint32 n_sub\nuint8 n_rows\nuint8 n_cols\nuint8 bw\n"
        "uint8 mcs 0\nint32 rssi\nuint32 fc\nuint32 seq_num\nfloat64[] csi_real\n"
        "float64[] csi_imag\nstring rx_id\nuint32 msg_id\n"
        "=====\nMSG: std_msgs/Header\n# comment\nbuiltin_interfaces/msg/Time stamp\n"
        "string frame_id\n=====\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";
    EXPECT_TRUE(ros2::sameDefinition(ros2::wifiType(), commented, why)) << why;
    // ...fields do, at any depth.
    std::string swapped = commented;
    swapped.replace(swapped.find("float64[] csi_real"), 18, "float32[] csi_real");
    EXPECT_FALSE(ros2::sameDefinition(ros2::wifiType(), swapped, why));
    EXPECT_NE(why.find("csi_real"), std::string::npos) << why;
    std::string oldTime = commented;
    oldTime.replace(oldTime.find("uint32 nanosec"), 14, "uint32 nsec");
    EXPECT_FALSE(ros2::sameDefinition(ros2::wifiType(), oldTime, why));
    EXPECT_NE(why.find("builtin_interfaces/Time"), std::string::npos) << why;
    std::string noHeader = commented.substr(0, commented.find("=====\nMSG"));
    EXPECT_FALSE(ros2::sameDefinition(ros2::wifiType(), noHeader, why));
    EXPECT_NE(why.find("missing"), std::string::npos) << why;
    EXPECT_FALSE(ros2::sameDefinition(ros2::wifiType(), ros2::bearingType().definition, why));
}

// ---- bags written by independent code
namespace
{
namespace fs = std::filesystem;

std::string npmTools()
{
    for (const std::string d : {MRPT_WIFI_NPM_TOOLS, MRPT_WIFI_NPM_TOOLS_IN_SOURCE})
        if (fs::exists(d + "/node_modules/@mcap/core/package.json") &&
            fs::exists(d + "/node_modules/@foxglove/rosmsg2-serialization/package.json"))
            return d;
    return {};
}

// Empty when node, the npm packages (scripts/install-deps.sh) and Debian's lz4 are there, else
// what is missing.
std::string missingTools()
{
    if (test::run("node --version").exitCode != 0) return "node (Debian's nodejs)";
    if (npmTools().empty()) return "the npm packages in build/npm-tools";
    if (test::run("lz4 --version").exitCode != 0) return "Debian's lz4 program";
    return {};
}

#define MRPT_WIFI_REQUIRE_ROS2_TOOLS()                         \
    if (const auto missing = missingTools(); !missing.empty()) \
    GTEST_SKIP() << "needs " << missing << " (scripts/install-deps.sh installs them)"

test::CommandResult writer(const std::string& args)
{
    return test::run(
        "NPM_TOOLS=" + npmTools() + " node " + test::sourceDir() +
        "/tests/sensor/ros2_bag_writer.mjs " + args);
}

/** A frame as ros2_bag_writer.mjs wrote it (expected.txt). */
struct Expected
{
    std::string rxId, frameId, mac;
    uint64_t sec = 0, nsec = 0;
    unsigned chan = 0, nSub = 0, nRows = 0, nCols = 0, bw = 0, mcs = 0, fc = 0, seqNum = 0,
             msgId = 0, apId = 0;
    int rssi = 0;
    std::vector<double> re, im;
};

std::vector<Expected> readExpected(const std::string& path)
{
    std::ifstream in(path);
    std::vector<Expected> out;
    for (std::string line; std::getline(in, line);)
    {
        std::istringstream words(line);
        std::string kind;
        words >> kind;
        if (kind == "frame")
        {
            Expected e;
            words >> e.rxId >> e.sec >> e.nsec >> e.frameId >> e.mac >> e.chan >> e.nSub >>
                e.nRows >> e.nCols >> e.bw >> e.mcs >> e.rssi >> e.fc >> e.seqNum >> e.msgId >>
                e.apId;
            out.push_back(e);
        }
        else if (kind == "re" || kind == "im")
            for (double v; words >> v;) (kind == "re" ? out.back().re : out.back().im).push_back(v);
    }
    return out;
}

std::vector<CObservationWiFiCSI::Ptr> framesOf(const std::string& rawlog)
{
    std::vector<CObservationWiFiCSI::Ptr> frames;
    decodeCsiFile(rawlog, "auto", {}, [&](auto&& f) { frames.push_back(f); });
    return frames;
}

// Every field of every frame against what the writer wrote, matched by (rx_id, msg_id); each
// expected frame exactly once.
void expectSameFrames(
    const std::vector<CObservationWiFiCSI::Ptr>& frames, const std::vector<Expected>& expected)
{
    ASSERT_EQ(frames.size(), expected.size());
    std::map<std::pair<std::string, unsigned>, const Expected*> byKey;
    for (const auto& e : expected) byKey[{e.rxId, e.msgId}] = &e;
    ASSERT_EQ(byKey.size(), expected.size());
    for (const auto& f : frames)
    {
        const auto it = byKey.find({f->routerAddress, f->firmwareCounter});
        ASSERT_NE(it, byKey.end()) << f->routerAddress << " " << f->firmwareCounter;
        const Expected& e = *it->second;
        byKey.erase(it);
        SCOPED_TRACE(e.rxId + " msg " + std::to_string(e.msgId));
        EXPECT_EQ(f->sensorLabel, "WIFI_CSI_" + e.rxId);
        EXPECT_EQ(f->chanspec.asString(), std::to_string(e.chan) + "/" + std::to_string(e.bw));
        EXPECT_EQ(f->nfft(), e.nSub);
        EXPECT_EQ(f->nRx, e.nRows);
        EXPECT_EQ(f->nTx, e.nCols);
        const auto mac = MacAddress::fromString(e.mac);
        EXPECT_EQ(f->transmitter, mac);
        EXPECT_EQ(int(f->rssi_dBm), e.rssi);
        EXPECT_EQ(f->frameControl, e.fc);
        EXPECT_EQ(f->sequenceNumber, e.seqNum >> 4);
        EXPECT_EQ(f->fragmentNumber, e.seqNum & 15);
        EXPECT_EQ(f->source, "wiros");
        // The stamp (or the bag's time where it is 0) to the clock's resolution.
        EXPECT_NEAR(
            mrpt::Clock::toDouble(f->timestamp), double(e.sec) + 1e-9 * double(e.nsec), 1e-6);
        ASSERT_EQ(e.re.size(), size_t(e.nSub) * e.nRows * e.nCols);
        ASSERT_EQ(e.im.size(), e.re.size());
        for (unsigned tx = 0; tx < e.nCols; ++tx)
            for (unsigned rx = 0; rx < e.nRows; ++rx)
            {
                bool any = false;
                for (unsigned k = 0; k < e.nSub; ++k)
                {
                    const size_t i = k + size_t(e.nSub) * (rx + size_t(e.nRows) * tx);
                    any |= e.re[i] != 0 || e.im[i] != 0;
                    ASSERT_EQ(
                        f->at(tx, rx, k),
                        CObservationWiFiCSI::Complex(float(e.re[i]), float(e.im[i])))
                        << "tx " << tx << " rx " << rx << " k " << k;
                }
                EXPECT_EQ(f->isPresent(tx, rx), any) << "tx " << tx << " rx " << rx;
            }
    }
}

void flipByte(const std::string& path, uint64_t offset)
{
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(std::streamoff(offset));
    char c = 0;
    f.read(&c, 1);
    c = char(c ^ 0x5a);
    f.seekp(std::streamoff(offset));
    f.write(&c, 1);
}

bool contains(const std::string& text, const std::string& part)
{
    return text.find(part) != std::string::npos;
}
}  // namespace

TEST(Ros2Messages, ForeignCdrReaderDecodesOurDefinitionAndBytes)
{
    MRPT_WIFI_REQUIRE_ROS2_TOOLS();
    // @foxglove/rosmsg parses our definition, @foxglove/rosmsg2-serialization reads our bytes
    // with it and writes the very same bytes back.
    test::TempDir tmp;
    const auto m = sampleWifi();
    const auto bytes = ros2::serializeCdr(m);
    std::ofstream(tmp.file("def.txt")) << ros2::wifiType().definition;
    std::ofstream(tmp.file("msg.bin"), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    const auto r = writer("decode " + tmp.file("def.txt") + " " + tmp.file("msg.bin"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ofstream(tmp.file("decoded.txt")) << r.output;
    const auto decoded = readExpected(tmp.file("decoded.txt"));
    ASSERT_EQ(decoded.size(), 1u) << r.output.substr(0, 300);
    const Expected& e = decoded[0];
    EXPECT_EQ(e.rxId, m.rxId);
    EXPECT_EQ(e.sec, m.header.stampSec);
    EXPECT_EQ(e.nsec, m.header.stampNsec);
    EXPECT_EQ(e.frameId, m.header.frameId);
    EXPECT_EQ(e.mac, "02:00:00:00:0a:01");
    EXPECT_EQ(e.chan, m.chan);
    EXPECT_EQ(e.nSub, m.nSub);
    EXPECT_EQ(e.nRows, m.nRows);
    EXPECT_EQ(e.nCols, m.nCols);
    EXPECT_EQ(e.bw, m.bw);
    EXPECT_EQ(e.mcs, m.mcs);
    EXPECT_EQ(e.rssi, m.rssi);
    EXPECT_EQ(e.fc, m.fc);
    EXPECT_EQ(e.seqNum, m.seqNum);
    EXPECT_EQ(e.msgId, m.msgId);
    EXPECT_EQ(e.apId, m.apId);
    EXPECT_EQ(e.re, m.csiReal);
    EXPECT_EQ(e.im, m.csiImag);
    std::string hex;
    for (uint8_t b : bytes)
    {
        const char* digits = "0123456789abcdef";
        hex += digits[b >> 4], hex += digits[b & 15];
    }
    EXPECT_TRUE(contains(r.output, "reencoded " + hex + "\n")) << "foxglove writes other bytes";
}

TEST(Rosbag2, McapFromIndependentWriterImportsEveryField)
{
    MRPT_WIFI_REQUIRE_ROS2_TOOLS();
    test::TempDir tmp;
    const std::string bag = tmp.file("bag");
    const auto w = writer("mcap " + bag);
    ASSERT_EQ(w.exitCode, 0) << w.output;
    const auto expected = readExpected(bag + "/expected.txt");
    ASSERT_EQ(expected.size(), 12u);

    // The bag directory: both files (metadata.yaml's list), every chunk compression, with and
    // without a summary; both receivers on either topic, the other type skipped, the bad
    // messages counted.
    const auto in =
        test::run(test::binDir() + "/csi-import -q " + bag + " " + tmp.file("all.rawlog"));
    EXPECT_EQ(in.exitCode, 3) << in.output;  // malformed messages skipped
    EXPECT_TRUE(contains(in.output, "format: rosbag2, records 16 (4 without CSI skipped)"))
        << in.output;
    EXPECT_TRUE(contains(
        in.output,
        "2 storage files, 20 messages; MCAP chunks: lz4 2 none 2 zstd 2; 9 CRCs "
        "checked; 1 MCAP without summary"))
        << in.output;
    EXPECT_TRUE(contains(in.output, "other message types skipped: std_msgs/msg/String (4)"))
        << in.output;
    EXPECT_TRUE(
        contains(in.output, "skipped 2 malformed records: rf_msgs/msg/Wifi whose sizes disagree"))
        << in.output;
    EXPECT_TRUE(
        contains(in.output, "skipped 2 malformed records: rf_msgs/msg/Wifi of another definition"))
        << in.output;
    EXPECT_TRUE(contains(in.output, "'192.168.50.2' -> WIFI_CSI_192.168.50.2")) << in.output;
    expectSameFrames(framesOf(tmp.file("all.rawlog")), expected);

    // One file alone (no summary), and strict mode stopping at the first bad message.
    const auto one = test::run(
        test::binDir() + "/csi-import -q " + bag + "/bag_1.mcap " + tmp.file("one.rawlog"));
    EXPECT_EQ(one.exitCode, 3) << one.output;
    expectSameFrames(
        framesOf(tmp.file("one.rawlog")),
        std::vector<Expected>(expected.begin() + 6, expected.end()));
    const auto strict = test::run(
        test::binDir() + "/csi-import -q --strict " + bag + "/bag_1.mcap " +
        tmp.file("strict.rawlog"));
    EXPECT_EQ(strict.exitCode, 1) << strict.output;
    EXPECT_TRUE(contains(strict.output, "bag_1.mcap")) << strict.output;
    EXPECT_TRUE(contains(strict.output, "(/csi, t=")) << strict.output;
}

TEST(Rosbag2, CorruptMcapIsNamedAndKeepsWhatCameBefore)
{
    MRPT_WIFI_REQUIRE_ROS2_TOOLS();
    test::TempDir tmp;
    const std::string bag = tmp.file("bag");
    ASSERT_EQ(writer("mcap " + bag).exitCode, 0);
    const auto sizeOf = [](const std::string& p) { return uint64_t(fs::file_size(p)); };
    // Footer (9 + 20 bytes) and magic (8) end every file; DataEnd (9 + 4) comes before the
    // footer in a file without summary.
    const std::string noSummary = tmp.file("data-crc.mcap");
    fs::copy_file(bag + "/bag_1.mcap", noSummary);
    flipByte(noSummary, sizeOf(noSummary) - 8 - 29 - 1);
    auto r = test::run(test::binDir() + "/csi-import -q " + noSummary + " " + tmp.file("a.rawlog"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_TRUE(contains(r.output, "data-crc.mcap' at byte ")) << r.output;
    EXPECT_TRUE(contains(r.output, "data section CRC mismatch")) << r.output;
    EXPECT_EQ(framesOf(tmp.file("a.rawlog")).size(), 6u);  // all read before the DataEnd

    const std::string summary = tmp.file("summary-crc.mcap");
    fs::copy_file(bag + "/bag_0.mcap", summary);
    flipByte(summary, sizeOf(summary) - 8 - 1);
    r = test::run(test::binDir() + "/csi-import -q " + summary + " " + tmp.file("b.rawlog"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_TRUE(contains(r.output, "summary CRC mismatch")) << r.output;

    // Cut in the middle (a recording killed): the messages before the cut are kept.
    const std::string cut = tmp.file("cut.mcap");
    fs::copy_file(bag + "/bag_0.mcap", cut);
    fs::resize_file(cut, sizeOf(cut) / 8);  // in the second chunk
    r = test::run(test::binDir() + "/csi-import -q " + cut + " " + tmp.file("c.rawlog"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_TRUE(contains(r.output, "cut.mcap' at byte ")) << r.output;
    EXPECT_TRUE(contains(r.output, "truncated")) << r.output;
    const auto kept = framesOf(tmp.file("c.rawlog")).size();
    EXPECT_GE(kept, 1u);
    EXPECT_LT(kept, 6u);
}

TEST(Rosbag2, SqliteFromIndependentWriterImportsEveryField)
{
    MRPT_WIFI_REQUIRE_ROS2_TOOLS();
    test::TempDir tmp;
    const std::string work = tmp.file("work");
    const auto w = writer("sqlite-input " + work);
    ASSERT_EQ(w.exitCode, 0) << w.output;
    const auto py = test::run(
        "/usr/bin/python3 " + test::sourceDir() + "/tests/sensor/ros2_sqlite_bag.py " + work +
        "/messages.json " + tmp.file("bag"));
    ASSERT_EQ(py.exitCode, 0) << py.output;
    const auto expected = readExpected(work + "/expected.txt");
    ASSERT_EQ(expected.size(), 6u);
    // The bag directory (metadata.yaml) and the .db3 alone read the same.
    for (const std::string& input : {tmp.file("bag"), tmp.file("bag") + "/bag_0.db3"})
    {
        SCOPED_TRACE(input);
        const auto in =
            test::run(test::binDir() + "/csi-import -q " + input + " " + tmp.file("s.rawlog"));
        EXPECT_EQ(in.exitCode, 3) << in.output;
        EXPECT_TRUE(contains(in.output, "format: rosbag2, records 8 (2 without CSI skipped)"))
            << in.output;
        EXPECT_TRUE(contains(in.output, "1 storage file, 10 messages")) << in.output;
        EXPECT_TRUE(contains(in.output, "other message types skipped: std_msgs/msg/String (2)"))
            << in.output;
        // The inconsistent message, and the float32 one (SQLite has no definitions to tell).
        EXPECT_TRUE(contains(in.output, "2 malformed records skipped")) << in.output;
        EXPECT_TRUE(contains(in.output, "(first at message id ")) << in.output;
        const auto frames = framesOf(tmp.file("s.rawlog"));
        expectSameFrames(frames, expected);
        // Stored in reverse: read in time order, as rosbag2 plays them.
        EXPECT_TRUE(std::is_sorted(
            frames.begin(), frames.end(),
            [](const auto& a, const auto& b) { return a->timestamp < b->timestamp; }));
    }
    // An Iron bag keeps each type's definition: the right one reads the same, an older
    // rf_msgs (float32 CSI) under the same name makes every Wifi message malformed.
    for (const std::string variant : {"iron", "iron-float32-wifi"})
    {
        SCOPED_TRACE(variant);
        const std::string dir = tmp.file(variant);
        ASSERT_EQ(
            test::run(
                "/usr/bin/python3 " + test::sourceDir() + "/tests/sensor/ros2_sqlite_bag.py " +
                work + "/messages.json " + dir + " " + variant)
                .exitCode,
            0);
        const auto in = test::run(test::binDir() + "/csi-import -q " + dir + " " + dir + ".rawlog");
        if (variant == "iron")
        {
            EXPECT_EQ(in.exitCode, 3) << in.output;
            expectSameFrames(framesOf(dir + ".rawlog"), expected);
        }
        else
        {
            EXPECT_EQ(in.exitCode, 6) << in.output;  // no frame at all
            EXPECT_TRUE(contains(
                in.output, "skipped 8 malformed records: rf_msgs/msg/Wifi of another definition"))
                << in.output;
        }
    }

    // Not a bag: an SQLite file without rosbag2's tables, an empty directory.
    const auto other = test::run(
        "/usr/bin/python3 -c \"import sqlite3; sqlite3.connect('" + tmp.file("x.db3") +
        "').execute('CREATE TABLE t(a)')\"");
    ASSERT_EQ(other.exitCode, 0) << other.output;
    auto r = test::run(
        test::binDir() + "/csi-import -q " + tmp.file("x.db3") + " " + tmp.file("x.rawlog"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_TRUE(contains(r.output, "x.db3' is an SQLite file without rosbag2's")) << r.output;
    fs::create_directory(tmp.file("empty"));
    r = test::run(
        test::binDir() + "/csi-import -q " + tmp.file("empty") + " " + tmp.file("e.rawlog"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_TRUE(contains(r.output, "empty' is a directory without a ROS 2 bag")) << r.output;
}
