/* mrpt_wifi — MCAP output (issue 55) read back by independent code: npm's @mcap/core (indexed
 * and stream readers), @foxglove/rosmsg and @foxglove/rosmsg2-serialization through
 * tests/sensor/mcap_check.mjs, compared field by field with the data the file came from. */
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/sensor/LocalizationMcap.h>
#include <mrpt_wifi/sensor/McapReader.h>
#include <mrpt_wifi/sensor/McapWriter.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "../support/SyntheticCsi.h"
#include "../support/TestSupport.h"

using namespace mrpt_wifi;

namespace
{
std::string npmTools()
{
    for (const char* d : {MRPT_WIFI_NPM_TOOLS, MRPT_WIFI_NPM_TOOLS_IN_SOURCE})
        if (std::filesystem::exists(std::string(d) + "/node_modules/@mcap/core")) return d;
    return {};
}

/** Empty when node and the npm packages are there; else why not (CI must have them). */
std::string missingTools()
{
    if (test::run("node --version").exitCode != 0) return "no node (scripts/install-deps.sh)";
    if (npmTools().empty())
        return "no npm packages in " + std::string(MRPT_WIFI_NPM_TOOLS) +
               " (scripts/install-deps.sh)";
    return {};
}

#define REQUIRE_NPM_TOOLS()                            \
    if (const auto why = missingTools(); !why.empty()) \
    {                                                  \
        if (std::getenv("CI")) FAIL() << why;          \
        GTEST_SKIP() << why;                           \
    }

test::CommandResult checkMcap(const std::string& mcap, const std::string& expectedJson)
{
    return test::run(
        "NODE_PATH=" + npmTools() + "/node_modules node " + test::sourceDir() +
        "/tests/sensor/mcap_check.mjs " + mcap + " " + expectedJson);
}

std::string num(double v)
{
    char b[40];
    std::snprintf(b, sizeof(b), "%.17g", v);
    return b;
}
std::string quoted(const std::string& s)
{
    return "\"" + s + "\"";
}

/** What csi-export must make of a timestamp: whole seconds and rounded nanoseconds. */
std::pair<int64_t, uint32_t> stampOf(mrpt::Clock::time_point t)
{
    const double s = mrpt::Clock::toDouble(t);
    auto sec = int64_t(std::floor(s));
    auto ns = int64_t(std::llround((s - std::floor(s)) * 1e9));
    if (ns >= 1000000000) ++sec, ns -= 1000000000;
    return {sec, uint32_t(ns)};
}
std::string headerJson(mrpt::Clock::time_point t)
{
    const auto [sec, ns] = stampOf(t);
    return "{\"stamp\":{\"sec\":" + std::to_string(sec) + ",\"nanosec\":" + std::to_string(ns) +
           "},\"frame_id\":\"\"}";
}
std::string logTimeJson(mrpt::Clock::time_point t)
{
    const auto [sec, ns] = stampOf(t);
    return quoted(std::to_string(uint64_t(sec) * 1000000000ull + ns));
}
std::string macJson(const MacAddress& m)
{
    std::string s = "[";
    for (size_t i = 0; i < m.bytes.size(); ++i) s += (i ? "," : "") + std::to_string(m.bytes[i]);
    return s + "]";
}

/** rf_msgs/msg/Wifi as WiROS fills it, computed here from the observation (not through the
 *  project's converter): csi column-major over (subcarrier, rx, tx), absent pairs zero. */
std::string wifiJson(const CObservationWiFiCSI& o, const std::string& rxId)
{
    std::ostringstream re, im;
    const unsigned n = o.nfft();
    for (unsigned tx = 0; tx < o.nTx; ++tx)
        for (unsigned rx = 0; rx < o.nRx; ++rx)
            for (unsigned k = 0; k < n; ++k)
            {
                const auto v = o.isPresent(tx, rx) ? o.at(tx, rx, k) : std::complex<float>();
                const bool first = tx == 0 && rx == 0 && k == 0;
                re << (first ? "" : ",") << num(v.real());
                im << (first ? "" : ",") << num(v.imag());
            }
    std::ostringstream s;
    s << "{\"header\":" << headerJson(o.timestamp)
      << ",\"ap_id\":0,\"txmac\":" << macJson(o.transmitter)
      << ",\"chan\":" << unsigned(o.chanspec.centerChannel) << ",\"n_sub\":" << n
      << ",\"n_rows\":" << unsigned(o.nRx) << ",\"n_cols\":" << unsigned(o.nTx)
      << ",\"bw\":" << unsigned(o.chanspec.bandwidthMHz)
      << ",\"mcs\":0,\"rssi\":" << int(o.rssi_dBm) << ",\"fc\":" << unsigned(o.frameControl)
      << ",\"seq_num\":" << (unsigned(o.sequenceNumber) << 4 | o.fragmentNumber)
      << ",\"csi_real\":[" << re.str() << "],\"csi_imag\":[" << im.str()
      << "],\"rx_id\":" << quoted(rxId) << ",\"msg_id\":0}";
    return s.str();
}

std::string bearingJson(const CObservationWiFiBearing& b)
{
    return "{\"header\":" + headerJson(b.timestamp) +
           ",\"ap_id\":0,\"txmac\":" + macJson(b.transmitter) +
           ",\"n_tx\":0,\"n_rx\":0,\"seq\":0,\"rssi\":[" + std::to_string(int(b.rssi_dBm)) +
           "],\"aoa\":[" + num(b.aoa_rad) + "]}";
}

const char* kWifiFields =
    "[\"header:Header\",\"ap_id:uint8\",\"txmac:uint8[]\",\"chan:uint8\",\"n_sub:uint32\","
    "\"n_rows:uint8\",\"n_cols:uint8\",\"bw:uint8\",\"mcs:uint8\",\"rssi:int32\",\"fc:uint32\","
    "\"seq_num:uint32\",\"csi_real:float64[]\",\"csi_imag:float64[]\",\"rx_id:string\","
    "\"msg_id:uint32\"]";
const char* kBearingFields =
    "[\"header:Header\",\"ap_id:uint8\",\"txmac:uint8[]\",\"n_tx:uint8\",\"n_rx:uint8\","
    "\"seq:uint32\",\"rssi:int32[]\",\"aoa:float64[]\"]";

/** A rawlog as csi-bearings leaves it after csi-import of two receivers: CSI of both (one by
 *  router address, one by sensor label only; different sizes, an absent pair) and bearings,
 *  interleaved in time; over 1 MiB of CSI, so two chunks. Returns the expected messages (JSON
 *  array elements) in file order. */
std::vector<std::string> writeTwoReceiverRawlog(const std::string& path)
{
    std::vector<std::string> messages;
    mrpt::io::CFileGZOutputStream f(path);
    auto ar = mrpt::serialization::archiveFrom(f);
    const double t0 = 1732800000.125;
    for (int i = 0; i < 42; ++i)
    {
        const auto t = mrpt::Clock::fromDouble(t0 + 0.0371 * i);
        if (i % 3 == 2)
        {
            CObservationWiFiBearing b;
            b.timestamp = t;
            b.transmitter =
                MacAddress::fromString(i % 2 ? "02:00:00:00:0a:01" : "02:00:00:00:0b:02");
            b.chanspec = Chanspec::make(155, 80);
            b.rssi_dBm = int8_t(-40 - i);
            b.aoa_rad = 0.1 * i - 1.2;
            ar << b;
            messages.push_back(
                "{\"topic\":\"/bearing\",\"logTime\":" + logTimeJson(t) +
                ",\"message\":" + bearingJson(b) + "}");
            continue;
        }
        const bool a = i % 2 == 0;
        auto o = a ? test::syntheticFrame(4, 4, 80, uint16_t(100 + i), "00:12:34:56:78:9b")
                   : test::syntheticFrame(2, 3, 40, uint16_t(200 + i), "00:12:34:56:78:9c");
        o->timestamp = t;
        o->fragmentNumber = uint8_t(i % 4);
        o->frameControl = 0x88;
        o->rssi_dBm = int8_t(-50 - i);
        if (a)
            o->routerAddress = "192.168.50.1";
        else
        {
            o->sensorLabel = "RX_B";
            o->setPresent(1, 2, false);
        }
        ar << *o;
        messages.push_back(
            "{\"topic\":\"/csi\",\"logTime\":" + logTimeJson(t) +
            ",\"message\":" + wifiJson(*o, a ? "192.168.50.1" : "RX_B") + "}");
    }
    return messages;
}

std::string expectedJson(const std::vector<std::string>& messages, const std::string& compression)
{
    std::string s = "{\"profile\":\"ros2\",\"compression\":" + quoted(compression) +
                    ",\"schemas\":{\"rf_msgs/msg/Wifi\":" + kWifiFields +
                    ",\"rf_msgs/msg/Bearing\":" + kBearingFields +
                    "},\"channels\":["
                    "{\"topic\":\"/csi\",\"schema\":\"rf_msgs/msg/Wifi\",\"messageEncoding\":"
                    "\"cdr\",\"metadataKeys\":[\"offered_qos_profiles\"]},"
                    "{\"topic\":\"/bearing\",\"schema\":\"rf_msgs/msg/Bearing\","
                    "\"messageEncoding\":\"cdr\",\"metadataKeys\":[\"offered_qos_profiles\"]}"
                    "],\"messages\":[";
    for (size_t i = 0; i < messages.size(); ++i) s += (i ? "," : "") + messages[i];
    return s + "]}";
}
}  // namespace

TEST(McapExport, CsiAndBearingsOfTwoReceiversReadByIndependentReaders)
{
    REQUIRE_NPM_TOOLS();
    test::TempDir tmp;
    const auto messages = writeTwoReceiverRawlog(tmp.file("in.rawlog"));
    for (const std::string compression : {"zstd", "lz4", "none"})
    {
        SCOPED_TRACE(compression);
        const std::string out = tmp.file("out-" + compression + ".mcap");
        const auto run = test::run(
            test::binDir() + "/csi-export -q " + tmp.file("in.rawlog") + " --mcap " + out +
            " --compression " + compression);
        ASSERT_EQ(run.exitCode, 0) << run.output;
        EXPECT_NE(
            run.output.find("28 rf_msgs/msg/Wifi on /csi, 14 rf_msgs/msg/Bearing on /bearing"),
            std::string::npos)
            << run.output;
        std::ofstream(tmp.file("expected.json"))
            << expectedJson(messages, compression == "none" ? "" : compression);
        const auto check = checkMcap(out, tmp.file("expected.json"));
        EXPECT_EQ(check.exitCode, 0) << check.output;
        EXPECT_NE(check.output.find("OK "), std::string::npos) << check.output;
        std::cout << check.output;
    }
}

TEST(McapExport, RxIdOptionAndErrorsNameTheFile)
{
    REQUIRE_NPM_TOOLS();
    test::TempDir tmp;
    auto messages = writeTwoReceiverRawlog(tmp.file("in.rawlog"));
    // --rx-id overrides every frame's receiver, as with --bag.
    const auto run = test::run(
        test::binDir() + "/csi-export -q " + tmp.file("in.rawlog") + " --rx-id robot1 --mcap " +
        tmp.file("r.mcap"));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    for (auto& m : messages)
        for (const char* id : {"\"rx_id\":\"192.168.50.1\"", "\"rx_id\":\"RX_B\""})
            if (const auto p = m.find(id); p != std::string::npos)
                m.replace(p, std::strlen(id), "\"rx_id\":\"robot1\"");
    std::ofstream(tmp.file("expected.json")) << expectedJson(messages, "zstd");
    const auto check = checkMcap(tmp.file("r.mcap"), tmp.file("expected.json"));
    EXPECT_EQ(check.exitCode, 0) << check.output;

    // A folder that does not exist, a full disk, an unknown compression: exit 1 or 2, named.
    const auto noDir = test::run(
        test::binDir() + "/csi-export -q " + tmp.file("in.rawlog") + " --mcap " +
        tmp.file("no/such/dir.mcap"));
    EXPECT_NE(noDir.exitCode, 0);
    EXPECT_NE(noDir.output.find("no/such/dir.mcap"), std::string::npos) << noDir.output;
    if (std::filesystem::exists("/dev/full"))
    {
        const auto full = test::run(
            test::binDir() + "/csi-export -q " + tmp.file("in.rawlog") + " --mcap /dev/full");
        EXPECT_NE(full.exitCode, 0);
        EXPECT_NE(full.output.find("'/dev/full'"), std::string::npos) << full.output;
        EXPECT_NE(full.output.find("No space left"), std::string::npos) << full.output;
    }
    const auto badAlgo = test::run(
        test::binDir() + "/csi-export -q " + tmp.file("in.rawlog") + " --mcap " +
        tmp.file("x.mcap") + " --compression brotli");
    EXPECT_NE(badAlgo.exitCode, 0);
    EXPECT_NE(badAlgo.output.find("brotli"), std::string::npos) << badAlgo.output;
}

TEST(McapWriter, ManySmallChunksOutOfOrderAcrossChannels)
{
    REQUIRE_NPM_TOOLS();
    test::TempDir tmp;
    // Small chunks: many chunk indexes and message indexes; messages out of order across
    // channels (the indexed reader must still return them by time).
    {
        mcap::WriterOptions o;
        o.compression = mcap::Compression::Lz4;
        o.chunkSize = 64;
        mcap::Writer w(tmp.file("small.mcap"), o);
        const auto a = w.addChannel(w.addSchema("t/msg/A", "ros2msg", "uint8 v\n"), "/a", "cdr");
        const auto b = w.addChannel(w.addSchema("t/msg/A", "ros2msg", "uint8 v\n"), "/b", "cdr");
        EXPECT_EQ(w.addSchema("t/msg/A", "ros2msg", "uint8 v\n"), 1);
        for (uint8_t i = 0; i < 20; ++i)
        {
            const std::vector<uint8_t> cdr = {0, 1, 0, 0, i};
            w.write(i % 2 ? a : b, 1000 + 10 * i, cdr);
        }
        w.close();
    }
    std::string msgs;
    for (int i = 0; i < 20; ++i)
        msgs += std::string(i ? "," : "") + "{\"topic\":\"" + (i % 2 ? "/a" : "/b") +
                "\",\"logTime\":\"" + std::to_string(1000 + 10 * i) +
                "\",\"message\":{\"v\":" + std::to_string(i) + "}}";
    std::ofstream(tmp.file("small.json"))
        << "{\"profile\":\"ros2\",\"compression\":\"lz4\",\"schemas\":{\"t/msg/A\":[\"v:uint8\"]},"
           "\"channels\":[{\"topic\":\"/a\",\"schema\":\"t/msg/A\",\"messageEncoding\":\"cdr\","
           "\"metadataKeys\":[]},{\"topic\":\"/b\",\"schema\":\"t/msg/A\",\"messageEncoding\":"
           "\"cdr\",\"metadataKeys\":[]}],\"messages\":["
        << msgs << "]}";
    const auto check = checkMcap(tmp.file("small.mcap"), tmp.file("small.json"));
    EXPECT_EQ(check.exitCode, 0) << check.output;
    EXPECT_NE(check.output.find("in 10 lz4 chunks"), std::string::npos) << check.output;
}

TEST(LocalizationMcap, LongRunPathIsThinnedEvenlyAndEndsAtTheLastPose)
{
    // An hour of live poses at 100/s must not all stay in memory for /path: it holds at most
    // kMaxPathPoses, evenly spaced from the first pose, plus the last; /pose keeps every one.
    const std::string file = test::tempPath(".mcap");
    constexpr size_t kPoses = 25003;
    {
        ros2::LocalizationMcap out(file, false, mcap::Compression::None);
        for (size_t i = 0; i < kPoses; ++i)
            out.pose(1.7e9 + 0.01 * double(i), 0.001 * double(i), 0, 0);
        out.close();
    }
    std::vector<uint64_t> stamps;  // /path's pose stamps in hundredths of a second
    size_t posesOnPoseTopic = 0;
    auto source = mcap::openFileSource(file);
    mcap::readMcap(
        *source,
        [&](const mcap::MessageView& m)
        {
            posesOnPoseTopic += m.channel->topic == "/pose";
            if (m.channel->topic != "/path") return;
            // CDR (little endian, 4-byte encapsulation): Header{int32 sec, uint32 nanosec,
            // string frame_id}, then sequence<PoseStamped>; doubles 8-aligned from the payload.
            const uint8_t* p = m.data + 4;
            const size_t n = m.size - 4;
            size_t at = 0;
            const auto u32 = [&]
            {
                at = (at + 3) & ~size_t(3);
                uint32_t v;
                std::memcpy(&v, p + at, 4);
                at += 4;
                return v;
            };
            const auto header = [&]
            {
                const uint32_t sec = u32(), nsec = u32();
                at += u32();  // frame_id with its NUL
                return uint64_t(sec) * 100 + uint64_t(std::llround(nsec * 1e-7));
            };
            header();
            const uint32_t count = u32();
            for (uint32_t k = 0; k < count; ++k)
            {
                stamps.push_back(header());
                at = (at + 7) & ~size_t(7);
                at += 7 * 8;  // position, orientation
                ASSERT_LE(at, n);
            }
        });
    EXPECT_EQ(posesOnPoseTopic, kPoses);
    ASSERT_GT(stamps.size(), ros2::LocalizationMcap::kMaxPathPoses / 2);
    ASSERT_LE(stamps.size(), ros2::LocalizationMcap::kMaxPathPoses + 1);
    const uint64_t first = uint64_t(1700000000) * 100;
    EXPECT_EQ(stamps.front(), first);
    EXPECT_EQ(stamps.back(), first + kPoses - 1);
    // Evenly spaced (one stride) up to the last pose.
    const uint64_t stride = stamps[1] - stamps[0];
    EXPECT_GE(stride, 2u);
    for (size_t k = 1; k + 1 < stamps.size(); ++k) EXPECT_EQ(stamps[k] - stamps[k - 1], stride);
}
