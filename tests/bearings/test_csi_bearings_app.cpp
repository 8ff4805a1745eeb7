/* csi-bearings end to end on a short simulated recording: output rawlog, CSV, pictures; bad
 * input (unknown algorithm, calibration for another channel/device, array not matching the CSI)
 * fails before any work with a clear message. */
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationBearingRange.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <filesystem>
#include <fstream>
#include <map>

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

/** 2 s of the bearing scenario as a rawlog (CSI + odometry). */
const std::string& simulatedRawlog()
{
    static test::TempDir dir;
    static std::string path;
    if (!path.empty()) return path;
    auto sc = sim::Scenario::fromYamlFile(test::sourceDir() + "/share/scenarios/bearing.yaml");
    sc.duration_s = 2.0;
    sim::Simulator s(sc);
    path = dir.file("in.rawlog");
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
    EXPECT_NE(r.output.find("no phase calibration"), std::string::npos) << r.output;
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
