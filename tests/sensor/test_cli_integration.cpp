// End-to-end: the command-line programs on real and generated captures, and Debian's
// rawlog-edit loading the observation plugin.
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>
#include <mrpt_wifi/sensor/PcapIO.h>

#include <fstream>
#include <regex>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using test::run;

namespace
{
std::string pcap2rawlog()
{
    return test::binDir() + "/csi-pcap2rawlog -q ";
}
std::string csiExport()
{
    return test::binDir() + "/csi-export -q ";
}
std::string rawlogEdit()
{
    return "rawlog-edit -p " + test::libDir() + "/libmrpt_wifi_obs.so ";
}

/** A capture of `n` 4x4 frames from two transmitters, one datagram lost. */
void writeCapture(const std::string& path, uint16_t n)
{
    PcapWriter w(path);
    for (uint16_t seq = 0; seq < n; ++seq)
    {
        auto frame = test::syntheticFrame(
            4, 4, 80, seq, seq % 2 ? "02:00:00:00:00:02" : "02:00:00:00:00:01");
        auto datagrams = nexmon::encodeFrame(*frame);
        if (seq == 3) datagrams.erase(datagrams.begin() + 7);
        for (const auto& d : datagrams)
            w.writeUdp(d.data(), d.size(), mrpt::Clock::fromDouble(100.0 + seq * 0.01));
    }
}

size_t rawlogObjectCount(const std::string& infoOutput)
{
    std::smatch m;
    static const std::regex re("Overall number of objects\\s*:\\s*(\\d+)");
    return std::regex_search(infoOutput, m, re) ? size_t(std::stoul(m[1])) : size_t(-1);
}
}  // namespace

TEST(CliIntegration, HelpExitsZero)
{
    for (const auto& prog : {pcap2rawlog(), csiExport()})
    {
        const auto r = run(prog + "--help");
        EXPECT_EQ(r.exitCode, 0) << r.output;
        EXPECT_NE(r.output.find("USAGE"), std::string::npos) << r.output;
    }
    EXPECT_NE(run(pcap2rawlog() + "--no-such-flag a b").exitCode, 0);
}

TEST(CliIntegration, Pcap2RawlogThenDebianRawlogEditDescribesIt)
{
    test::TempDir tmp;
    writeCapture(tmp.file("in.pcap"), 20);
    const auto conv =
        run(pcap2rawlog() + tmp.file("in.pcap") + " " + tmp.file("out.rawlog") +
            " --sensor-label CSI_TOP --sensor-pose 0.1 0 0.4 90 0 0");
    ASSERT_EQ(conv.exitCode, 0) << conv.output;
    EXPECT_NE(conv.output.find("CSI frames: 20"), std::string::npos) << conv.output;
    EXPECT_NE(conv.output.find("incomplete 1, missing pairs 1"), std::string::npos) << conv.output;

    const auto info = run(rawlogEdit() + "--info -i " + tmp.file("out.rawlog"));
    ASSERT_EQ(info.exitCode, 0) << info.output;
    EXPECT_EQ(rawlogObjectCount(info.output), 20u) << info.output;
    EXPECT_NE(info.output.find("CSI_TOP"), std::string::npos) << info.output;

    const auto describe = run(rawlogEdit() + "--describe -i " + tmp.file("out.rawlog"));
    ASSERT_EQ(describe.exitCode, 0) << describe.output;
    EXPECT_NE(describe.output.find("mrpt_wifi::CObservationWiFiCSI"), std::string::npos);
    EXPECT_NE(describe.output.find("02:00:00:00:00:02"), std::string::npos);
    EXPECT_NE(describe.output.find("channel 155 / 80 MHz"), std::string::npos);
    EXPECT_NE(describe.output.find("MISSING"), std::string::npos);  // the lost datagram
    // The pose given in degrees arrives as 90 deg yaw.
    EXPECT_NE(describe.output.find("[0.100000 0.000000 0.400000 90.000000"), std::string::npos)
        << describe.output.substr(0, 3000);

    // Without the plugin MRPT cannot read the class: the plugin is what makes it work.
    const auto noPlugin = run("rawlog-edit --info -i " + tmp.file("out.rawlog"));
    EXPECT_NE(
        noPlugin.output.find("'mrpt_wifi::CObservationWiFiCSI' which is not registered"),
        std::string::npos)
        << noPlugin.output;
}

TEST(CliIntegration, RawlogEditExportTxt)
{
    test::TempDir tmp;
    writeCapture(tmp.file("in.pcap"), 5);
    ASSERT_EQ(run(pcap2rawlog() + tmp.file("in.pcap") + " " + tmp.file("out.rawlog")).exitCode, 0);
    // rawlog-edit names the output after the input; run it inside the folder.
    const auto r =
        run("cd " + tmp.path().string() + " && " + rawlogEdit() + "--export-txt -i out.rawlog");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream txt(tmp.file("out_WIFI_CSI.txt"));
    ASSERT_TRUE(txt) << r.output;
    std::string line;
    size_t rows = 0;
    while (std::getline(txt, line))
    {
        if (line.empty() || line[0] == '%') continue;
        std::istringstream cols(line);
        size_t n = 0;
        for (std::string c; cols >> c;) ++n;
        EXPECT_EQ(n, 1u + 9u + 4u * 4u * 234u * 2u);  // time + metadata + re/im
        ++rows;
    }
    EXPECT_EQ(rows, 5u);
}

TEST(CliIntegration, CsiExportJsonLinesMatchesTheDecoder)
{
    test::TempDir tmp;
    writeCapture(tmp.file("in.pcap"), 4);
    ASSERT_EQ(run(pcap2rawlog() + tmp.file("in.pcap") + " " + tmp.file("out.rawlog")).exitCode, 0);
    for (const char* input : {"in.pcap", "out.rawlog"})
    {
        const auto r = run(csiExport() + tmp.file(input) + " --jsonl " + tmp.file("out.jsonl"));
        ASSERT_EQ(r.exitCode, 0) << r.output;
        std::ifstream f(tmp.file("out.jsonl"));
        std::vector<std::string> lines;
        for (std::string l; std::getline(f, l);) lines.push_back(l);
        ASSERT_EQ(lines.size(), 4u) << input;
        // A transmitter's first frame waits for its second (stream learning): find by seq.
        const auto bySeq = [&](int seq)
        {
            for (const auto& l : lines)
                if (l.find("\"seq\":" + std::to_string(seq) + ",") != std::string::npos) return l;
            return std::string();
        };
        for (const char* key :
             {"\"timestamp\":", "\"seq\":1,", "\"mac\":\"02:00:00:00:00:02\"", "\"rssi\":-48",
              "\"chanspec\":57499", "\"channel\":155", "\"bw\":80", "\"nfft\":256", "\"chip\":106",
              "\"n_rx\":4", "\"n_tx\":4", "\"present\":[[true,true,true,true],", "\"csi\":[[[["})
            EXPECT_NE(bySeq(1).find(key), std::string::npos)
                << key << " in " << bySeq(1).substr(0, 400);
        // The first value of frame 0, tx 0, rx 0, bin 0 as the decoder gives it.
        std::vector<CObservationWiFiCSI::Ptr> frames;
        readCsiFrames(
            tmp.file("in.pcap"), {}, [&](CObservationWiFiCSI::Ptr&& o) { frames.push_back(o); });
        char first[64];
        std::snprintf(
            first, sizeof(first), "\"csi\":[[[[%.9g,%.9g]", frames[0]->at(0, 0, 0).real(),
            frames[0]->at(0, 0, 0).imag());
        EXPECT_NE(bySeq(0).find(first), std::string::npos) << first;
        // Frame 3 lost core 1 / stream 3: shown as missing.
        EXPECT_NE(
            bySeq(3).find("\"present\":[[true,true,true,true],[true,true,true,true],[true,true,"
                          "true,true],[true,false,true,true]]"),
            std::string::npos)
            << bySeq(3).substr(0, 400);
    }
}

TEST(CliIntegration, RealCaptureConvertsAndDescribes)
{
    MRPT_WIFI_REQUIRE_REAL_CAPTURE(path, "ubilocate_4x4_80mhz.pcap");
    test::TempDir tmp;
    const auto conv =
        run(pcap2rawlog() + path + " " + tmp.file("real.rawlog") + " --format ubilocate");
    ASSERT_EQ(conv.exitCode, 0) << conv.output;
    const auto info = run(rawlogEdit() + "--info -i " + tmp.file("real.rawlog"));
    EXPECT_EQ(rawlogObjectCount(info.output), 9u) << info.output;
    // The capture is UbiLocate: forcing the current-firmware header rejects every datagram.
    const auto wrong =
        run(pcap2rawlog() + path + " " + tmp.file("wrong.rawlog") + " --format nexmon");
    // All skipped: no frame at all, which is "no result" (6) rather than "some skipped" (3).
    EXPECT_EQ(wrong.exitCode, cli::kExitNoMatchingFrames) << wrong.output;
    EXPECT_NE(wrong.output.find("size not matching bandwidth: 144"), std::string::npos)
        << wrong.output;
}

TEST(CliIntegration, BadInputNamesTheFileAndKeepsWhatWasConverted)
{
    test::TempDir tmp;
    writeCapture(tmp.file("in.pcap"), 10);
    const auto full = test::readFile(tmp.file("in.pcap"));
    // Cut inside frame 6's datagrams.
    const size_t record = (full.size() - 24) / (10 * 16 - 1);
    const size_t cut = 24 + record * (6 * 16 + 3) + 200;
    std::ofstream(tmp.file("cut.pcap"), std::ios::binary).write(full.data(), std::streamsize(cut));

    // A capture that was stopped: converted up to the cut, which is a note naming its offset.
    const auto r = run(pcap2rawlog() + tmp.file("cut.pcap") + " " + tmp.file("cut.rawlog"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("the last record (byte "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("is truncated"), std::string::npos) << r.output;
    // Frames 0..5 complete + frame 6 partial are in a rawlog MRPT reads.
    const auto info = run(rawlogEdit() + "--info -i " + tmp.file("cut.rawlog"));
    EXPECT_EQ(rawlogObjectCount(info.output), 7u) << info.output;

    std::ofstream(tmp.file("notes.txt")) << "hello\n";
    const auto notPcap = run(pcap2rawlog() + tmp.file("notes.txt") + " " + tmp.file("x.rawlog"));
    EXPECT_NE(notPcap.exitCode, 0);
    EXPECT_NE(notPcap.output.find("notes.txt"), std::string::npos) << notPcap.output;

    const auto missing = run(pcap2rawlog() + tmp.file("nope.pcap") + " " + tmp.file("x.rawlog"));
    EXPECT_NE(missing.exitCode, 0);
    EXPECT_NE(missing.output.find("nope.pcap"), std::string::npos) << missing.output;

    const auto badFormat =
        run(pcap2rawlog() + tmp.file("in.pcap") + " " + tmp.file("x.rawlog") + " --format nexmon5");
    EXPECT_NE(badFormat.exitCode, 0);
    EXPECT_NE(badFormat.output.find("nexmon5"), std::string::npos) << badFormat.output;

    const auto badPose = run(
        pcap2rawlog() + tmp.file("in.pcap") + " " + tmp.file("x.rawlog") + " --sensor-pose 1 2 3");
    EXPECT_NE(badPose.exitCode, 0) << badPose.output;

    // A corrupt rawlog: csi-export names it and the byte offset.
    auto rawlog = test::readFile(tmp.file("cut.rawlog"));
    ASSERT_EQ(
        run(pcap2rawlog() + tmp.file("in.pcap") + " " + tmp.file("plain.rawlog")).exitCode, 0);
    const auto junk = run(csiExport() + tmp.file("notes.txt") + " --jsonl " + tmp.file("x.jsonl"));
    EXPECT_NE(junk.exitCode, 0) << junk.output;
    EXPECT_NE(junk.output.find("notes.txt"), std::string::npos) << junk.output;
}

TEST(CliIntegration, ACaptureWithoutCsiIsAFailureAScriptSees)
{
    // A capture with no CSI datagram (tcpdump on the wrong interface): no result, exit 6.
    test::TempDir tmp;
    {
        PcapWriter w(tmp.file("empty.pcap"));
    }
    auto r = run(pcap2rawlog() + tmp.file("empty.pcap") + " " + tmp.file("x.rawlog"));
    EXPECT_EQ(r.exitCode, cli::kExitNoMatchingFrames) << r.output;
    EXPECT_NE(r.output.find("no CSI frame in"), std::string::npos) << r.output;
    r = run(csiExport() + tmp.file("empty.pcap") + " --stats");
    EXPECT_EQ(r.exitCode, cli::kExitNoMatchingFrames) << r.output;
    // One frame is enough for success.
    writeCapture(tmp.file("one.pcap"), 1);
    EXPECT_EQ(run(pcap2rawlog() + tmp.file("one.pcap") + " " + tmp.file("y.rawlog")).exitCode, 0);
}
