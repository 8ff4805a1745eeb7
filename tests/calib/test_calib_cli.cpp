/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-calibrate end to end: rawlogs made by wifi-sim, the calibration file in its folder
 * layout, the report, --check, and bad input rejected before any work. */
#include <gtest/gtest.h>
#include <mrpt/system/filesystem.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "CalibTestSupport.h"
#include "TestSupport.h"

namespace
{
const std::string kBin = MRPT_WIFI_BIN_DIR;
const std::string kArrays = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/";

using Run = mrpt_wifi::test::SeparateOutputs;
Run run(const std::string& command)
{
    return mrpt_wifi::test::runSeparately(command);
}

/** Simulates a drive into DIR/drive.rawlog with ground truth in DIR/truth. */
std::string simulate(const calibtest::DriveSpec& d, const std::string& dir)
{
    mrpt::system::createDirectory(dir);
    std::ofstream(dir + "/scenario.yaml") << calibtest::scenarioText(d);
    const auto r =
        run(kBin + "/wifi-sim -q " + dir + "/scenario.yaml " + dir + "/drive.rawlog --truth-dir " +
            dir + "/truth");
    EXPECT_EQ(r.rc, 0) << r.err;
    return dir + "/drive.rawlog";
}

class CalibCli : public ::testing::Test
{
protected:
    static void SetUpTestSuite()
    {
        root_ = mrpt_wifi::test::tempPath() + "_calibcli";
        mrpt::system::createDirectory(root_);
        calibtest::DriveSpec d;
        d.duration_s = 40;
        d.odometry = true;
        good_ = simulate(d, root_ + "/good");
    }
    static std::string root_, good_;
    const std::string cal_ = kBin + "/wifi-calibrate -q ";
};
std::string CalibCli::root_, CalibCli::good_;
}  // namespace

TEST_F(CalibCli, CalibratesWritesFileReportAndChecks)
{
    const std::string out = root_ + "/calib", rep = root_ + "/report";
    const auto r =
        run(cal_ + good_ + " --array " + kArrays + "rt-ac86u.yaml --transmitters " + root_ +
            "/good/truth/transmitters.yaml --poses " + root_ +
            "/good/truth/trajectory_tum.txt --out " + out + " --report " + rep);
    ASSERT_EQ(r.rc, 0) << r.out << r.err;
    const std::string file = out + "/rt-ac86u/ch155_80mhz.yaml";
    EXPECT_TRUE(mrpt::system::fileExists(file)) << r.out;
    EXPECT_NE(r.out.find("bearing error"), std::string::npos);
    EXPECT_TRUE(mrpt::system::fileExists(rep + "/phases_ch155_80mhz.png"));
    EXPECT_TRUE(mrpt::system::fileExists(rep + "/bearing_error_ch155_80mhz.png"));
    const auto c = mrpt_wifi::PhaseCalibration::fromYamlFile(file);
    EXPECT_EQ(c.device, "rt-ac86u");
    EXPECT_EQ(c.antennas(), 4u);
    EXPECT_GT(c.framesUsed, 3000u);

    const auto chk =
        run(cal_ + good_ + " --array " + kArrays + "rt-ac86u.yaml --transmitters " + root_ +
            "/good/truth/transmitters.yaml --poses " + root_ +
            "/good/truth/trajectory_tum.txt --check " + out);
    EXPECT_EQ(chk.rc, 0) << chk.out << chk.err;
    EXPECT_NE(chk.out.find("OK"), std::string::npos) << chk.out;

    // Another receiver (other seed → other phase offsets) against this file: stale, exit 3.
    calibtest::DriveSpec other;
    other.seed = 99;
    other.duration_s = 20;
    const std::string otherLog = simulate(other, root_ + "/other");
    const auto stale =
        run(cal_ + otherLog + " --array " + kArrays + "rt-ac86u.yaml --tx-position 7 5 --poses " +
            root_ + "/other/truth/trajectory_tum.txt --check " + out);
    EXPECT_EQ(stale.rc, 3) << stale.out << stale.err;
    EXPECT_NE(stale.err.find("recalibrate"), std::string::npos) << stale.err;
}

TEST_F(CalibCli, OdometryPosesWithOrigin)
{
    // The odometry starts at (0,0,0) at the robot's start pose (9.5, 5, 180°).
    const auto r = run(
        cal_ + good_ + " --array " + kArrays +
        "rt-ac86u.yaml --tx-position 7 5 --odom-origin 9.5 5 180 --out " + root_ + "/calib_odo");
    EXPECT_EQ(r.rc, 0) << r.out << r.err;
    EXPECT_TRUE(mrpt::system::fileExists(root_ + "/calib_odo/rt-ac86u/ch155_80mhz.yaml"));
}

TEST_F(CalibCli, BadInputFailsBeforeAnyWork)
{
    const std::string arr = " --array " + kArrays + "rt-ac86u.yaml";
    const std::string out = " --out " + root_ + "/bad";
    struct Case
    {
        std::string args, expect;
    };
    calibtest::DriveSpec d;
    d.duration_s = 5;
    const std::string noOdo = simulate(d, root_ + "/noodo");  // odometry disabled
    const std::vector<Case> cases = {
        {noOdo + arr + " --tx-position 7 5" + out, "no robot poses"},
        {good_ + arr + " --tx-position 7 5 --mac 02:00:00:00:00:99" + out, "never appears"},
        {good_ + " --array " + kArrays + "ap-linear-2.yaml --tx-position 7 5" + out,
         "receive chains"},
        {good_ + arr + " --tx-position 7 5 --channel 36/80" + out, "no frames on channel"},
        {good_ + arr + out, "exactly one of --tx-position"},
        {good_ + arr + " --tx-position 7 x" + out, "expected 2 numbers"},
        {good_ + arr + " --tx-position 7 5 --poses /nonexistent.txt" + out, "cannot open"},
        {root_ + "/missing.rawlog" + arr + " --tx-position 7 5" + out, "cannot open"},
    };
    for (const auto& c : cases)
    {
        const auto r = run(cal_ + c.args);
        EXPECT_EQ(r.rc, 1) << c.args << "\n" << r.out << r.err;
        EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
        EXPECT_EQ(r.out.find("Channel"), std::string::npos) << "did work: " << r.out;
    }
    EXPECT_FALSE(mrpt::system::directoryExists(root_ + "/bad"));
}

TEST_F(CalibCli, UnobservableDriveWritesNothingUnlessForced)
{
    calibtest::DriveSpec d;
    d.motion = "static";
    d.duration_s = 20;
    const std::string log = simulate(d, root_ + "/static");
    const std::string args = cal_ + log + " --array " + kArrays +
                             "rt-ac86u.yaml --tx-position 7 5 --poses " + root_ +
                             "/static/truth/trajectory_tum.txt --out " + root_ + "/static_cal";
    const auto r = run(args);
    EXPECT_EQ(r.rc, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("distinct bearings"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("NOT written"), std::string::npos);
    const std::string file = root_ + "/static_cal/rt-ac86u/ch155_80mhz.yaml";
    EXPECT_FALSE(mrpt::system::fileExists(file));
    const auto f = run(args + " --force");
    EXPECT_EQ(f.rc, 0) << f.out << f.err;
    EXPECT_TRUE(mrpt::system::fileExists(file));
}

TEST_F(CalibCli, Help)
{
    const auto r = run(cal_ + "--help");
    EXPECT_EQ(r.rc, 0);
    EXPECT_NE(r.out.find("--static-splitter"), std::string::npos);
}

namespace
{
/** Columns of a csi-bearings CSV: {has_aod, aod_deg} per row. */
std::vector<std::pair<std::string, std::string>> aodCells(const std::string& csv)
{
    std::istringstream in(mrpt_wifi::test::readFile(csv));
    std::string line;
    std::getline(in, line);  // header
    std::vector<std::pair<std::string, std::string>> out;
    while (std::getline(in, line))
    {
        std::vector<std::string> cells;
        std::string cell;
        std::istringstream ls(line);
        while (std::getline(ls, cell, ',')) cells.push_back(cell);
        if (cells.size() > 10) out.emplace_back(cells[9], cells[10]);
    }
    return out;
}
}  // namespace

TEST_F(CalibCli, TransmitChainsAndAodOnlyWhereCalibrated)
{
    // One 4-stream AP on a wall facing the room, the robot driving in front of it.
    const std::string dir = root_ + "/txchains";
    mrpt::system::createDirectory(dir);
    std::ofstream(dir + "/scenario.yaml")
        << "name: txchains\nduration_s: 20\nseed: 31\n"
           "room:\n  corners: [[0, 0], [14, 0], [14, 10], [0, 10]]\n"
           "  reflection: {magnitude: 0.35, phase_deg: 180}\n"
           "transmitters:\n  - {name: ap, mac: '02:11:22:33:44:01', position: [0.3, 5.0],"
           " yaw_deg: 0, channel: 155/80, streams: 4, array: "
        << kArrays
        << "ap-linear-4.yaml}\n"
           "receiver:\n  array: "
        << kArrays
        << "rt-ac86u.yaml\n  sensor_pose: {x: 0.1, y: 0.0, z: 0.4, yaw_deg: 0}\n"
           "motion:\n  type: random_walk\n  start: [4.0, 5.0, 0]\n  center: [4.0, 5.0]\n"
           "  radius_m: 3.0\n  speed_mps: 0.6\n  turn_rate_dps: 90\n"
           "impairments:\n  snr_db: 25\n";
    ASSERT_EQ(
        run(kBin + "/wifi-sim -q " + dir + "/scenario.yaml " + dir + "/drive.rawlog -t " + dir +
            "/truth")
            .rc,
        0);
    const std::string common = dir + "/drive.rawlog --array " + kArrays +
                               "rt-ac86u.yaml --transmitters " + dir + "/truth/transmitters.yaml";

    // --transmit-chains needs the transmitters' list (with yaw and array).
    const auto bad =
        run(cal_ + dir + "/drive.rawlog --array " + kArrays +
            "rt-ac86u.yaml --tx-position 0.3 5 --transmit-chains --out " + dir + "/x");
    EXPECT_EQ(bad.rc, 1);
    EXPECT_NE(bad.err.find("--transmit-chains needs"), std::string::npos) << bad.err;

    const std::string out = dir + "/calib";
    const auto r =
        run(cal_ + common + " --poses " + dir +
            "/truth/trajectory_tum.txt --transmit-chains --out " + out);
    ASSERT_EQ(r.rc, 0) << r.out << r.err;
    const std::string txFile = out + "/transmitters/02-11-22-33-44-01/ch155_80mhz.yaml";
    ASSERT_TRUE(mrpt::system::fileExists(txFile)) << r.out;
    const auto c = mrpt_wifi::PhaseCalibration::fromYamlFile(txFile);
    EXPECT_EQ(c.role, mrpt_wifi::PhaseCalibration::Role::Transmitter);
    EXPECT_EQ(c.antennas(), 4u);
    EXPECT_GT(c.aodResidual_rad, 0);
    EXPECT_NE(r.out.find("AoD error"), std::string::npos) << r.out;

    const std::string bearings = kBin + "/csi-bearings -q " + dir +
                                 "/drive.rawlog /dev/null --algo aod --stride 25 --tx-array " +
                                 kArrays + "ap-linear-4.yaml ";
    // Receiver calibrated, transmit chains not: no AoD, empty cells, and the reason.
    const auto gated =
        run(bearings + "--calib " + out + "/rt-ac86u/ch155_80mhz.yaml --csv " + dir + "/gated.csv");
    ASSERT_EQ(gated.rc, 0) << gated.err;
    EXPECT_NE(gated.out.find("not calibrated"), std::string::npos) << gated.out;
    const auto g = aodCells(dir + "/gated.csv");
    ASSERT_GT(g.size(), 50u);
    for (const auto& [has, aod] : g)
    {
        EXPECT_EQ(has, "0");
        EXPECT_EQ(aod, "");
    }
    // --uncalibrated-aod: reported anyway.
    const auto raw = run(bearings + "--uncalibrated-aod --csv " + dir + "/raw.csv");
    ASSERT_EQ(raw.rc, 0) << raw.err;
    EXPECT_NE(raw.out.find("uncalibrated (--uncalibrated-aod)"), std::string::npos) << raw.out;
    for (const auto& [has, aod] : aodCells(dir + "/raw.csv")) EXPECT_EQ(has, "1");
    // The calibration folder: AoD with the transmit-chain calibration.
    const auto cal = run(bearings + "--calib " + out + " --csv " + dir + "/cal.csv");
    ASSERT_EQ(cal.rc, 0) << cal.err;
    EXPECT_NE(cal.out.find("with its transmit-chain calibration"), std::string::npos) << cal.out;
    const auto k = aodCells(dir + "/cal.csv");
    ASSERT_GT(k.size(), 50u);
    for (const auto& [has, aod] : k)
    {
        EXPECT_EQ(has, "1");
        EXPECT_NE(aod, "");
    }
}

TEST_F(CalibCli, EveryChannelOfAHoppingDriveCalibratedAndUsedAtOnce)
{
    // share/scenarios/hopping.yaml: APs on 42/80, 155/80 and 6/20, the receive chains' offsets
    // moving from channel to channel with their delays. One drive, one file per channel, each
    // within 1° RMS of the simulator's truth; csi-bearings then uses all three at once.
    const std::string scenario =
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/scenarios/hopping.yaml";
    const std::string dir = root_ + "/hopping", out = dir + "/calib";
    mrpt::system::createDirectory(dir);
    auto r =
        run(kBin + "/wifi-sim -q -d 40 " + scenario + " " + dir + "/drive.rawlog --truth-dir " +
            dir + "/truth");
    ASSERT_EQ(r.rc, 0) << r.err;
    // The simulated receiver has no jump states, but the moving robot's multipath moves the
    // chains' delays by ~1 ns: with the shipped defaults, states that close to a chain's
    // reference are merged into it, and the files hold the plain per-subcarrier phases.
    const std::string calibrate =
        cal_ + dir + "/drive.rawlog --array " + kArrays + "rt-ac86u.yaml --transmitters " + dir +
        "/truth/transmitters.yaml --poses " + dir + "/truth/trajectory_tum.txt --out ";
    r = run(calibrate + out);
    ASSERT_EQ(r.rc, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("merged into it"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("no chain changed state during the drive"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("Channels (3 in the recording)"), std::string::npos) << r.out;

    mrpt_wifi::sim::Simulator truth(mrpt_wifi::sim::Scenario::fromYamlFile(scenario));
    std::map<std::string, double> meanOffset1_deg;
    for (const char* cs : {"42/80", "155/80", "6/20"})
    {
        const auto chanspec = mrpt_wifi::Chanspec::fromString(cs);
        const std::string file = mrpt_wifi::PhaseCalibration::pathFor(out, "rt-ac86u", chanspec);
        ASSERT_TRUE(mrpt::system::fileExists(file)) << cs << "\n" << r.out;
        const auto c = mrpt_wifi::PhaseCalibration::fromYamlFile(file);
        EXPECT_TRUE(c.chanspec.sameChannel(chanspec));
        const double rms = calibtest::phaseErrorRms_deg(c, truth.hardware());
        std::cout << "[ " << cs << " ] phase RMS error vs truth " << rms << " deg\n";
        EXPECT_LT(rms, 1.0) << cs;
        EXPECT_NE(r.out.find(std::string(cs) + " "), std::string::npos);
        meanOffset1_deg[cs] = c.phaseAt(1, 0) * 180 / M_PI;
    }
    // The channels' offsets differ (the chains' delays): one calibration could not serve all.
    EXPECT_GT(
        std::abs(mrpt_wifi::wrapAngle(
            (meanOffset1_deg["42/80"] - meanOffset1_deg["155/80"]) * M_PI / 180)),
        10 * M_PI / 180);

    // Bearings from every AP, each channel with its own calibration, none missing (on a few
    // seconds of the same receiver: the scenario's seed).
    r = run(kBin + "/wifi-sim -q -d 4 " + scenario + " " + dir + "/short.rawlog");
    ASSERT_EQ(r.rc, 0) << r.err;
    r =
        run(kBin + "/csi-bearings -q -a aoa_only --require-calib -c " + out + " " + dir +
            "/short.rawlog " + dir + "/bearings.rawlog");
    ASSERT_EQ(r.rc, 0) << r.out << r.err;
    for (const char* mac : {"02:00:00:00:06:01", "02:00:00:00:06:02", "02:00:00:00:06:03"})
    {
        const auto at = r.out.find(mac);
        ASSERT_NE(at, std::string::npos) << r.out;
        std::istringstream row(r.out.substr(at + std::strlen(mac)));
        uint64_t frames = 0, bearings = 0;
        row >> frames >> bearings;
        EXPECT_GT(bearings, frames / 2) << mac << "\n" << r.out;
    }
    // A channel without its file is named, with what to run.
    std::remove(mrpt_wifi::PhaseCalibration::pathFor(
                    out, "rt-ac86u", mrpt_wifi::Chanspec::fromString("6/20"))
                    .c_str());
    r =
        run(kBin + "/csi-bearings -q -a aoa_only -c " + out + " " + dir + "/short.rawlog " + dir +
            "/bearings2.rawlog");
    EXPECT_EQ(r.rc, 0) << r.err;
    EXPECT_NE(
        r.err.find("frames on 6/20 get uncalibrated bearings: no calibration for 6/20"),
        std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("run wifi-calibrate"), std::string::npos) << r.err;
    r =
        run(kBin + "/csi-bearings -q -a aoa_only --require-calib -c " + out + " " + dir +
            "/short.rawlog " + dir + "/bearings3.rawlog");
    EXPECT_NE(r.rc, 0);
    EXPECT_NE(r.err.find("6/20"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("ch6_20mhz.yaml"), std::string::npos) << r.err;
}
