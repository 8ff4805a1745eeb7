/* csi-bearings end to end on a short simulated recording: output rawlog, CSV, pictures; bad
 * input (unknown algorithm, calibration for another channel/device, array not matching the CSI)
 * fails before any work with a clear message. */
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationBearingRange.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "TestSupport.h"

using namespace mrpt_wifi;
namespace fs = std::filesystem;

namespace
{
std::string program()
{
    return test::binDir() + "/csi-bearings";
}
std::string arrays()
{
    return test::sourceDir() + "/share/arrays/";
}

/** 2 s of the bearing scenario as a rawlog (CSI + odometry) in `path`; with
 *  `calibrated`, without per-chain phase offsets, so bearings from any subset of the chains
 *  agree without a calibration. */
void simulateBearingScenario(const std::string& path, bool calibrated = false)
{
    auto sc = sim::Scenario::fromYamlFile(test::sourceDir() + "/share/scenarios/bearing.yaml");
    sc.duration_s = 2.0;
    if (calibrated) sc.impairments.antennaPhaseOffsets = false;
    sim::Simulator s(sc);
    mrpt::io::CFileGZOutputStream f(path);
    auto ar = mrpt::serialization::archiveFrom(f);
    sim::SimEvent ev;
    while (s.next(ev))
    {
        if (ev.kind == sim::SimEvent::Kind::Csi)
            ar << *ev.csi;
        else
            ar << *ev.odometry;
    }
}

const std::string& simulatedRawlog()
{
    static test::TempDir dir;
    static const std::string path = dir.file("in.rawlog");
    static const bool done = (simulateBearingScenario(path), true);
    (void)done;
    return path;
}

std::map<std::string, size_t> countClasses(const std::string& rawlog)
{
    std::map<std::string, size_t> n;
    mrpt::io::CFileGZInputStream f(rawlog);
    auto ar = mrpt::serialization::archiveFrom(f);
    for (;;)
    {
        try
        {
            auto obj = ar.ReadObject();
            ++n[obj->GetRuntimeClass()->className];
        }
        catch (...)
        {
            break;
        }
    }
    return n;
}
}  // namespace

TEST(BearingApp, HelpAndHappyPath)
{
    const auto help = test::run(program() + " --help");
    EXPECT_EQ(help.exitCode, 0);
    EXPECT_NE(help.output.find("--calib"), std::string::npos);

    test::TempDir tmp;
    const std::string out = tmp.file("out.rawlog"), csv = tmp.file("b.csv"), img = tmp.file("img");
    const auto r = test::run(
        program() + " " + simulatedRawlog() + " " + out + " --algo fft --csv " + csv +
        " --images " + img + " --image-every 40 --rawlog-images -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("02:00:00:00:02:01"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("Rejected frames"), std::string::npos) << r.output;
    const auto in = countClasses(simulatedRawlog());
    const auto n = countClasses(out);
    const size_t csi = in.at("mrpt_wifi::CObservationWiFiCSI");
    EXPECT_EQ(n.at("mrpt_wifi::CObservationWiFiCSI"), csi);
    EXPECT_EQ(n.at("mrpt::obs::CObservationOdometry"), in.at("mrpt::obs::CObservationOdometry"));
    EXPECT_EQ(n.at("mrpt_wifi::CObservationWiFiBearing"), csi);  // every frame gave one
    EXPECT_EQ(n.at("mrpt::obs::CObservationBearingRange"), csi);
    EXPECT_GT(n.at("mrpt::obs::CObservationImage"), 0u);
    const std::string text = test::readFile(csv);
    EXPECT_EQ(size_t(std::count(text.begin(), text.end(), '\n')), csi + 1);
    size_t pngs = 0;
    for (const auto& e : fs::directory_iterator(img)) pngs += e.path().extension() == ".png";
    EXPECT_GE(pngs, 6u);  // 3 transmitters × (CSI + profile)
}

TEST(BearingApp, UnknownAlgorithmOrOptionFailsBeforeWork)
{
    test::TempDir tmp;
    auto r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("o.rawlog") + " --algo nope -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("unknown bearing algorithm 'nope'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("spotfi"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(tmp.file("o.rawlog")));
    r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("o.rawlog") +
        " --algo music -p delay_bins=3 -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("unknown option 'delay_bins'"), std::string::npos) << r.output;
}

TEST(BearingApp, CalibrationForAnotherChannelOrDeviceFailsBeforeWork)
{
    test::TempDir tmp;
    PhaseCalibration c;
    c.device = "rt-ac86u";
    c.chanspec = Chanspec::make(42, 80);  // the recording is on 155/80
    c.subcarriers = {-122, 122};
    c.phases_rad.assign(4, {0.0, 0.0});
    const std::string wrongChannel = tmp.file("ch42.yaml");
    c.saveYamlFile(wrongChannel);
    auto r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("o.rawlog") + " --calib " +
        wrongChannel + " -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("42/80"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("155/80"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(tmp.file("o.rawlog")));

    c.chanspec = Chanspec::make(155, 80);
    c.device = "some-other-router";
    const std::string wrongDevice = tmp.file("dev.yaml");
    c.saveYamlFile(wrongDevice);
    r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("o.rawlog") + " --calib " +
        wrongDevice + " -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("some-other-router"), std::string::npos) << r.output;

    // A folder without a file for this channel: runs uncalibrated (and says so); with
    // --require-calib it refuses.
    fs::create_directories(tmp.file("calib/rt-ac86u"));
    r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("o2.rawlog") + " --calib " +
        tmp.file("calib") + " --require-calib -q");
    EXPECT_NE(r.exitCode, 0);
    // The channel, how many frames it holds and what to run.
    EXPECT_NE(r.output.find("frames on 155/80: no calibration for 155/80"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("ch155_80mhz.yaml"), std::string::npos) << r.output;
}

TEST(BearingApp, ArrayNotMatchingTheCsiFailsBeforeWork)
{
    test::TempDir tmp;
    // ap-linear-2 has 2 elements; the recording has 4 receive chains.
    const auto r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("o.rawlog") + " --array " + arrays() +
        "ap-linear-2.yaml -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("4 receive chains"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(tmp.file("o.rawlog")));
}

namespace
{
const std::string& calibratedRawlog()
{
    static test::TempDir dir;
    static const std::string path = dir.file("calibrated.rawlog");
    static const bool done = (simulateBearingScenario(path, true), true);
    (void)done;
    return path;
}

/** The calibrated recording as a router with only cores `keep` enabled would give it: each
 *  frame's rows for those cores, rxCores saying which. */
std::string withCores(const std::vector<uint8_t>& keep, const std::string& path)
{
    mrpt::io::CFileGZInputStream in(calibratedRawlog());
    auto ia = mrpt::serialization::archiveFrom(in);
    mrpt::io::CFileGZOutputStream out(path);
    auto oa = mrpt::serialization::archiveFrom(out);
    for (;;)
    {
        mrpt::serialization::CSerializable::Ptr obj;
        try
        {
            obj = ia.ReadObject();
        }
        catch (...)
        {
            break;
        }
        if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(obj))
        {
            auto cut = CObservationWiFiCSI::Create(*c);
            cut->resize(c->nTx, unsigned(keep.size()), c->nfft());
            for (unsigned m = 0; m < c->nTx; ++m)
                for (size_t r = 0; r < keep.size(); ++r)
                {
                    std::copy_n(c->pair(m, keep[r]), c->nfft(), cut->pair(m, unsigned(r)));
                    cut->setPresent(m, unsigned(r));
                }
            cut->rxCores = keep;
            cut->chainDelay_ns.clear();
            cut->chainState.clear();
            oa << *cut;
        }
        else
            oa << *obj;
    }
    return path;
}

/** Median AoA [deg] per transmitter from csi-bearings' CSV. */
std::map<std::string, double> medianAoa(const std::string& csv)
{
    std::map<std::string, std::vector<double>> v;
    std::istringstream lines(test::readFile(csv));
    std::string line;
    std::getline(lines, line);
    while (std::getline(lines, line))
    {
        std::vector<std::string> f;
        std::istringstream cells(line);
        for (std::string c; std::getline(cells, c, ',');) f.push_back(c);
        v[f.at(1)].push_back(std::stod(f.at(5)));
    }
    std::map<std::string, double> m;
    for (auto& [mac, a] : v)
    {
        std::nth_element(a.begin(), a.begin() + long(a.size() / 2), a.end());
        m[mac] = a[a.size() / 2];
    }
    return m;
}
}  // namespace

TEST(BearingApp, RouterWithSomeCoresGivesBearingsThroughAnArrayNamingThem)
{
    // Cores 0, 1, 3 of the simulated RT-AC86U (core mask 0xb). An array file naming them reads
    // the right rows: the bearings agree with those of all four chains.
    test::TempDir tmp;
    const std::string cut = withCores({0, 1, 3}, tmp.file("cores013.rawlog"));
    auto a = AntennaArray::fromYamlFile(arrays() + "rt-ac86u.yaml");
    a.name = "rt-ac86u";
    // Listed in another order than the rows: element i must read the row of core cores[i].
    a.elements = {a.elements[3], a.elements[0], a.elements[1]};
    a.cores = {3, 0, 1};
    const std::string arrayFile = tmp.file("rt-ac86u-013.yaml");
    std::ofstream(arrayFile) << a.asYamlText();

    auto r = test::run(
        program() + " " + calibratedRawlog() + " " + tmp.file("all.rawlog") + " --csv " +
        tmp.file("all.csv") + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = test::run(
        program() + " " + cut + " " + tmp.file("cut.rawlog") + " --array " + arrayFile + " --csv " +
        tmp.file("cut.csv") + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto all = medianAoa(tmp.file("all.csv")), some = medianAoa(tmp.file("cut.csv"));
    ASSERT_EQ(all.size(), 3u);
    ASSERT_EQ(some.size(), 3u);
    for (const auto& [mac, aoa] : all) EXPECT_NEAR(some.at(mac), aoa, 3.0) << mac;

    // The four-element array reads core 2, which isn't there: refused before any work, saying
    // what to write in the array file.
    r = test::run(program() + " " + cut + " " + tmp.file("o.rawlog") + " -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("cores: [0, 1, 3]"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(tmp.file("o.rawlog")));
}

TEST(BearingApp, NoBearingFromARecordingExitsNonZeroSayingWhy)
{
    // One receive chain: CSI but no angle of arrival in any frame.
    test::TempDir tmp;
    const std::string one = withCores({0}, tmp.file("core0.rawlog"));
    const auto r = test::run(program() + " " + one + " " + tmp.file("o.rawlog") + " -q");
    EXPECT_EQ(r.exitCode, 7) << r.output;
    EXPECT_NE(r.output.find("no bearing from the"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("one receive antenna"), std::string::npos) << r.output;
}

TEST(BearingApp, RealRouterWithCoreMask0xbGivesBearings)
{
    // muTrack D1 (RT-AC86U, cores 0, 1, 3): imported as it is, every frame gives a bearing.
    const std::string pcap =
        test::sharedDir().empty()
            ? std::string()
            : test::sharedDir() + "/data/mutrack/D1/D1_CSI_2G_20M_AP5_tr13.pcap";
    if (pcap.empty() || !fs::exists(pcap)) GTEST_SKIP() << "../shared/data/mutrack absent";
    test::TempDir tmp;
    auto r =
        test::run(test::binDir() + "/csi-import " + pcap + " " + tmp.file("in.rawlog") + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("complete 123, incomplete 0"), std::string::npos) << r.output;
    r = test::run(
        program() + " " + tmp.file("in.rawlog") + " " + tmp.file("o.rawlog") +
        " --array rt-ac86u-3core-57mm -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("(123 bearings)"), std::string::npos) << r.output;
}

TEST(BearingApp, DefaultEstimatorAndOdometry)
{
    test::TempDir tmp;
    // Without --algo: the recommended estimator, with the rawlog's odometry.
    const auto r = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("a.rawlog") + " --csv " +
        tmp.file("a.csv") + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("Algo  : default"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("poses from the rawlog"), std::string::npos) << r.output;
    EXPECT_NE(test::readFile(tmp.file("a.csv")).find(",default,"), std::string::npos);

    // --no-odometry: the rawlog's odometry (used above) ignored, as on a robot without any.
    const auto none = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("n.rawlog") + " --no-odometry --csv " +
        tmp.file("n.csv") + " -q");
    ASSERT_EQ(none.exitCode, 0) << none.output;
    EXPECT_NE(none.output.find("Odometry: none (--no-odometry"), std::string::npos) << none.output;
    EXPECT_NE(test::readFile(tmp.file("n.csv")).find(",default,"), std::string::npos);

    // A TUM file instead (same clock).
    const std::string tum = tmp.file("odo.txt");
    {
        std::ofstream f(tum);
        f << "# t x y z qx qy qz qw\n";
        for (int i = 0; i <= 40; ++i)
            f << std::fixed << 1700000000.0 + 0.05 * i << " " << 0.01 * i << " 0 0 0 0 0 1\n";
    }
    const auto t = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("b.rawlog") + " --odometry-tum " +
        tum + " -q");
    ASSERT_EQ(t.exitCode, 0) << t.output;
    EXPECT_NE(t.output.find("41 poses from " + tum), std::string::npos) << t.output;
    // ... which --no-odometry contradicts: refused before any output is written.
    const auto both = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("d.rawlog") + " --odometry-tum " +
        tum + " --no-odometry -q");
    EXPECT_NE(both.exitCode, 0);
    EXPECT_NE(both.output.find("--no-odometry and --odometry-tum"), std::string::npos)
        << both.output;
    EXPECT_FALSE(fs::exists(tmp.file("d.rawlog")));

    // A broken TUM file is refused, naming file and line, before any output is written.
    {
        std::ofstream f(tmp.file("bad.txt"));
        f << "1700000000 1 2\n";
    }
    const auto bad = test::run(
        program() + " " + simulatedRawlog() + " " + tmp.file("c.rawlog") + " --odometry-tum " +
        tmp.file("bad.txt") + " -q");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.output.find("bad.txt:1"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(tmp.file("c.rawlog")));
}
