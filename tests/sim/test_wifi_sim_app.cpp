/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-sim end to end: a readable rawlog, complete ground truth, a pcap whose datagrams decode
 * back to the rawlog's CSI, and bad input refused before anything is written. */
#include <gtest/gtest.h>
#include <mrpt/containers/yaml.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
const std::string kBin = MRPT_WIFI_BIN_DIR;
const std::string kShare = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";

struct Run
{
    int exitCode = -1;
    std::string output;
};

Run run(const std::string& args)
{
    Run r;
    FILE* p = popen((kBin + "/wifi-sim " + args + " 2>&1").c_str(), "r");
    if (!p) return r;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof(buf), p)) > 0) r.output.append(buf, n);
    const int status = pclose(p);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

std::string tempDir(const std::string& name)
{
    const std::string d = mrpt_wifi::test::tempPath() + "_" + name;
    mrpt::system::createDirectory(d);
    return d;
}

size_t countLines(const std::string& path, bool skipComments)
{
    std::ifstream f(path);
    std::string line;
    size_t n = 0;
    while (std::getline(f, line)) n += !(skipComments && !line.empty() && line[0] == '#');
    return n;
}

std::vector<mrpt::serialization::CSerializable::Ptr> readRawlog(const std::string& path)
{
    std::vector<mrpt::serialization::CSerializable::Ptr> objs;
    mrpt::io::CFileGZInputStream f(path);
    auto arch = mrpt::serialization::archiveFrom(f);
    for (;;)
    {
        try
        {
            objs.push_back(arch.ReadObject());
        }
        catch (const mrpt::serialization::CExceptionEOF&)
        {
            break;
        }
    }
    return objs;
}
}  // namespace

TEST(WifiSimApp, HelpExitsCleanly)
{
    const auto r = run("--help");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("--truth-dir"), std::string::npos);
}

TEST(WifiSimApp, WritesRawlogTruthAndPcap)
{
    const std::string dir = tempDir("wifisim");
    const auto r =
        run(kShare + "/scenarios/bearing.yaml " + dir + "/out.rawlog --truth-dir " + dir +
            "/truth --pcap " + dir + "/out.pcap --duration 2 --seed 9 -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;

    // Rawlog: time-ordered CSI (3 APs × 50 Hz × 2 s) and odometry (20 Hz).
    const auto objs = readRawlog(dir + "/out.rawlog");
    std::vector<CObservationWiFiCSI::Ptr> csi;
    size_t odometry = 0;
    double lastT = 0;
    for (const auto& o : objs)
    {
        if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
        {
            csi.push_back(c);
            EXPECT_GE(mrpt::Clock::toDouble(c->timestamp), lastT);
            lastT = mrpt::Clock::toDouble(c->timestamp);
        }
        else if (std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
            ++odometry;
        else
            ADD_FAILURE() << "unexpected " << o->GetRuntimeClass()->className;
    }
    EXPECT_NEAR(double(csi.size()), 300.0, 3.0);
    EXPECT_EQ(odometry, 41u);

    // Ground truth files.
    const std::string t = dir + "/truth/";
    EXPECT_EQ(countLines(t + "frames.csv", false), csi.size() + 1);
    EXPECT_EQ(countLines(t + "odometry_tum.txt", true), odometry);
    EXPECT_GE(countLines(t + "trajectory_tum.txt", true), 200u);
    const auto txs = mrpt::containers::yaml::FromFile(t + "transmitters.yaml");
    EXPECT_EQ(txs["transmitters"].size(), 3u);
    const auto imp = mrpt::containers::yaml::FromFile(t + "impairments.json");
    EXPECT_EQ(imp["seed"].as<int>(), 9);
    EXPECT_EQ(imp["hardware"]["channels"].size(), 1u);
    EXPECT_EQ(imp["hardware"]["channels"](0)["chains"].size(), 4u);
    EXPECT_EQ(
        imp["hardware"]["channels"](0)["chains"](0)["phase_rad_on_data_subcarriers"].size(), 234u);
    {
        std::ifstream f(t + "frames.csv");
        std::string header, row;
        std::getline(f, header);
        std::getline(f, row);
        EXPECT_NE(header.find("aoa_rad"), std::string::npos);
        EXPECT_NE(header.find("aod_rad"), std::string::npos);
        EXPECT_NE(header.find("los_delay_ns"), std::string::npos);
        EXPECT_NE(header.find("snr_db"), std::string::npos);
        EXPECT_EQ(
            std::count(header.begin(), header.end(), ','), std::count(row.begin(), row.end(), ','));
    }

    // Pcap: one datagram per (core, stream), decoding to the rawlog's CSI up to the packed-float
    // quantisation.
    std::map<std::pair<std::string, uint16_t>, CObservationWiFiCSI::Ptr> bySeq;
    size_t pairs = 0;
    for (const auto& c : csi)
    {
        bySeq[{c->transmitter.asString(), c->sequenceNumber}] = c;
        pairs += c->presentPairs();
    }
    PcapReader reader(dir + "/out.pcap");
    PcapUdpDatagram d;
    size_t datagrams = 0;
    double worst = 0;
    std::vector<std::complex<float>> decoded(256);
    while (reader.next(d))
    {
        nexmon::DatagramHeader h;
        nexmon::RejectReason why;
        ASSERT_TRUE(
            nexmon::parseHeader(d.payload, d.payloadLength, nexmon::FormatHint::Nexmon, h, why));
        ++datagrams;
        const auto it = bySeq.find({h.transmitter.asString(), h.sequenceNumber()});
        ASSERT_NE(it, bySeq.end());
        const auto& obs = *it->second;
        EXPECT_EQ(h.chanspec, obs.chanspec);
        EXPECT_EQ(h.rssi_dBm, obs.rssi_dBm);
        nexmon::decodeWords(d.payload + nexmon::csiOffset(), h.nfft(), decoded.data());
        for (unsigned b = 0; b < 256; ++b)
        {
            const auto o = obs.at(h.stream, h.core, b);
            const float scale = std::max(std::abs(o.real()), std::abs(o.imag()));
            worst = std::max(worst, double(std::abs(decoded[b] - o) / (scale + 1e-9f)));
        }
    }
    EXPECT_EQ(datagrams, pairs);
    EXPECT_LT(worst, 2e-3);
    mrpt::system::deleteFilesInDirectory(dir, true);
}

TEST(WifiSimApp, BadScenarioWritesNothing)
{
    const std::string dir = tempDir("wifisim_bad");
    std::ifstream in(kShare + "/scenarios/calibration.yaml");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    const auto pos = text.find("channel: 155/80");
    ASSERT_NE(pos, std::string::npos);
    text.replace(pos, 15, "channel: 155/90");
    const int line = 1 + int(std::count(text.begin(), text.begin() + long(pos), '\n'));
    std::ofstream(dir + "/bad.yaml") << text;
    const auto r = run(dir + "/bad.yaml " + dir + "/out.rawlog --truth-dir " + dir + "/truth");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(
        r.output.find("bad.yaml:" + std::to_string(line) + ": transmitters[0].channel"),
        std::string::npos)
        << r.output;
    EXPECT_FALSE(mrpt::system::fileExists(dir + "/out.rawlog"));
    EXPECT_FALSE(mrpt::system::directoryExists(dir + "/truth"));

    const auto missing = run(dir + "/nope.yaml " + dir + "/out.rawlog");
    EXPECT_NE(missing.exitCode, 0);
    EXPECT_NE(missing.output.find("nope.yaml"), std::string::npos);
    mrpt::system::deleteFilesInDirectory(dir, true);
}

TEST(WifiSimApp, RandomRoom)
{
    const std::string dir = tempDir("random_room");
    const auto r =
        run("--random-room 1001 " + dir + "/r.rawlog -d 3 -q --write-scenario " + dir + "/r.yaml");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("random-room-1001"), std::string::npos) << r.output;
    EXPECT_GT(readRawlog(dir + "/r.rawlog").size(), 100u);
    // The saved room is an ordinary scenario file giving the same recording.
    const auto again = run(dir + "/r.yaml " + dir + "/r2.rawlog -d 3 -q");
    ASSERT_EQ(again.exitCode, 0) << again.output;
    EXPECT_EQ(readRawlog(dir + "/r2.rawlog").size(), readRawlog(dir + "/r.rawlog").size());
    // Misuse is refused.
    EXPECT_NE(run("--random-room 1001 a.yaml " + dir + "/x.rawlog").exitCode, 0);
    EXPECT_NE(run("--random-room 0 " + dir + "/x.rawlog").exitCode, 0);
    EXPECT_NE(run("--write-scenario x.yaml a.yaml " + dir + "/x.rawlog").exitCode, 0);
    // A fourth AP is added to the same room; fewer than three, or without a room, are refused.
    const auto four =
        run("--random-room 1001 " + dir + "/r4.rawlog -d 1 -q --aps 4 --write-scenario " + dir +
            "/r4.yaml");
    ASSERT_EQ(four.exitCode, 0) << four.output;
    EXPECT_NE(
        mrpt::io::file_get_contents(dir + "/r4.yaml").find("02:00:00:00:0a:04"), std::string::npos);
    EXPECT_EQ(
        mrpt::io::file_get_contents(dir + "/r.yaml").find("02:00:00:00:0a:04"), std::string::npos);
    EXPECT_NE(run("--random-room 1001 " + dir + "/x.rawlog --aps 2").exitCode, 0);
    EXPECT_NE(run("a.yaml " + dir + "/x.rawlog --aps 4").exitCode, 0);
}
