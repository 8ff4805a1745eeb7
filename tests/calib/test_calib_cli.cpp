/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-calibrate end to end: rawlogs made by wifi-sim, the calibration file in its folder
 * layout, the report, --check, and bad input rejected before any work. */
#include <gtest/gtest.h>
#include <mrpt/system/filesystem.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "CalibTestSupport.h"
#include "TestSupport.h"

namespace
{
const std::string kBin = MRPT_WIFI_BIN_DIR;
const std::string kArrays = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/";

struct Run
{
    int rc = -1;
    std::string out, err;
};

std::string slurp(const std::string& path)
{
    std::ifstream f(path);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

Run run(const std::string& args)
{
    static int n = 0;
    const std::string base = mrpt_wifi::test::tempPath() + "_run" + std::to_string(n++);
    const int st = std::system((args + " >" + base + ".out 2>" + base + ".err").c_str());
    Run r;
    r.rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    r.out = slurp(base + ".out");
    r.err = slurp(base + ".err");
    return r;
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
