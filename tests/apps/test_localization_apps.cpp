/* mrpt_wifi — WiFi channel state information for MRPT.  */
// The command-line programs, and the map inside Debian's own pf-localization (LD_PRELOAD).
#include <gtest/gtest.h>
#include <mrpt/graphs/CNetworkOfPoses.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/RawlogIO.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "SyntheticWorld.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
const std::string kBin = MRPT_WIFI_BIN_DIR;
const std::string kLib = std::string(MRPT_WIFI_LIB_DIR) + "/libmrpt_wifi_localization.so";
const std::string kIni =
    std::string(MRPT_WIFI_SOURCE_DIR) + "/share/localization/pf-localization-wifi.ini";

struct Run
{
    int rc;
    std::string out;
};
Run run(const std::string& cmd)
{
    Run r{-1, {}};
    FILE* p = popen((cmd + " 2>&1").c_str(), "r");
    if (!p) return r;
    char buf[4096];
    while (size_t n = fread(buf, 1, sizeof(buf), p)) r.out.append(buf, n);
    const int st = pclose(p);
    r.rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

struct Fixture
{
    std::string dir;
    World w;
    Fixture()
    {
        dir = mrpt_wifi::test::tempPath() + "_apps";
        mrpt::system::createDirectory(dir);
        WorldOptions o;
        o.duration_s = 60;
        w = makeWorld(
            makeAps({{0.3, 4.7, -0.785}, {9.7, 4.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}}),
            o);
        std::ofstream(dir + "/aps.yaml") << w.aps.asYamlText();
        writeBearingCsv(dir + "/bearings.csv", w.bearings);
        w.odometry.saveTum(dir + "/odometry.txt");
        w.truth.saveTum(dir + "/truth.txt");
    }
};
const Fixture& fixture()
{
    static Fixture f;
    return f;
}
}  // namespace

TEST(LocalizationAppsCli, HelpWorks)
{
    for (const char* app :
         {"wifi-pf-localization", "wifi-graphslam", "wifi-iot-map", "wifi-bearings-synth"})
    {
        const auto r = run(kBin + "/" + app + " --help");
        EXPECT_EQ(r.rc, 0) << app << ": " << r.out;
        EXPECT_NE(r.out.find("USAGE"), std::string::npos) << app;
    }
}

TEST(LocalizationAppsPf, WifiPfLocalizationOnCsvInput)
{
    const auto& f = fixture();
    const auto r = run(
        kBin + "/wifi-pf-localization " + kIni + " -q --no-plots -n 1500 -m " + f.dir +
        "/aps.yaml -b " + f.dir + "/bearings.csv --odometry-tum " + f.dir +
        "/odometry.txt --sensor-pose 0.1 0 0 0 0 0 -g " + f.dir + "/truth.txt -o " + f.dir + "/pf");
    ASSERT_EQ(r.rc, 0) << r.out;
    EXPECT_NE(r.out.find("converged after"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("MET"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("NOT MET"), std::string::npos) << r.out;
    EXPECT_TRUE(mrpt::system::fileExists(f.dir + "/pf/estimate_tum.txt"));
}

TEST(LocalizationAppsPf, IniWithoutTheMapIsAnError)
{
    const auto& f = fixture();
    const std::string ini = f.dir + "/nomap.ini";
    std::ofstream(ini) << "[LocalizationExperiment]\nparticles_count=100\nlogOutput_dir=x\n"
                          "[MetricMap]\nwifiBearingMapp_count=1\n";
    const auto r =
        run(kBin + "/wifi-pf-localization " + ini + " -q -b " + f.dir +
            "/bearings.csv --odometry-tum " + f.dir + "/odometry.txt -o " + f.dir + "/pf2");
    EXPECT_EQ(r.rc, 1);
    EXPECT_NE(r.out.find("creates no wifiBearingMap"), std::string::npos) << r.out;
}

TEST(LocalizationAppsPf, DebianPfLocalizationWithLdPreload)
{
    if (!mrpt::system::fileExists("/usr/bin/pf-localization"))
        GTEST_SKIP() << "Debian's mrpt-apps (pf-localization) is not installed";
    const auto& f = fixture();
    writePfRawlog(f.dir + "/in.rawlog", f.w.bearings, f.w.odometry);
    {
        // pf-localization's ground truth: "t x y phi"; it takes the first column as time only
        // if the first two values aren't integers.
        std::ofstream gt(f.dir + "/gt.txt");
        gt.precision(15);
        for (size_t i = 1; i < f.w.truth.size(); ++i)
            gt << f.w.truth.t[i] << " " << f.w.truth.poses[i].x << " " << f.w.truth.poses[i].y
               << " " << f.w.truth.poses[i].phi << "\n";
    }
    std::string ini = mrpt::io::file_get_contents(kIni);
    auto set = [&](const std::string& key, const std::string& value)
    {
        const auto p = ini.find("\n" + key);
        ASSERT_NE(p, std::string::npos) << key;
        const auto e = ini.find('\n', p + 1);
        ini.replace(p + 1, e - p - 1, key + " = " + value);
    };
    set("particles_count", "1500");
    set("logOutput_dir", f.dir + "/preload");
    set("transmitters_file", f.dir + "/aps.yaml");
    set("SAVE_STATS_ONLY", "false\nground_truth_path_file = " + f.dir + "/gt.txt");
    std::ofstream(f.dir + "/preload.ini") << ini;
    const auto r =
        run("LD_PRELOAD=" + kLib + " /usr/bin/pf-localization " + f.dir + "/preload.ini " + f.dir +
            "/in.rawlog");
    ASSERT_EQ(r.rc, 0) << r.out.substr(r.out.size() > 3000 ? r.out.size() - 3000 : 0);
    EXPECT_NE(r.out.find("mrpt_wifi::CWiFiBearingMap"), std::string::npos)
        << "the map was not created inside pf-localization";
    std::ifstream e(f.dir + "/preload_000_0001500/GT_error.txt");
    std::vector<double> errs;
    for (double v; e >> v;) errs.push_back(v);
    ASSERT_GT(errs.size(), 100u);
    std::vector<double> late(errs.begin() + long(errs.size() / 3), errs.end());
    std::nth_element(late.begin(), late.begin() + long(late.size() / 2), late.end());
    EXPECT_LT(late[late.size() / 2], 0.3) << "median particle error after 20 s";
}

TEST(LocalizationAppsGraphSlam, CsvInputWritesGraphAndBeatsOdometry)
{
    const auto& f = fixture();
    const auto r =
        run(kBin + "/wifi-graphslam --no-plots -b " + f.dir + "/bearings.csv --odometry-tum " +
            f.dir + "/odometry.txt --aps " + f.dir + "/aps.yaml --sensor-pose 0.1 0 0 0 0 0 -g " +
            f.dir + "/truth.txt -o " + f.dir + "/gs");
    ASSERT_EQ(r.rc, 0) << r.out;
    EXPECT_NE(r.out.find("median ATE reduction"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("NOT MET"), std::string::npos) << r.out;
    mrpt::graphs::CNetworkOfPoses2DInf g;
    g.loadFromTextFile(f.dir + "/gs/solution.graph");
    EXPECT_GT(g.nodes.size(), 100u);
    EXPECT_GT(g.edges.size(), 100u);
}

TEST(LocalizationAppsGraphSlam, NonOverlappingTimestampsFailClearly)
{
    const auto& f = fixture();
    Trajectory2D late;
    late.push_back(1800000000.0, {0, 0, 0});
    late.push_back(1800000001.0, {1, 0, 0});
    late.saveTum(f.dir + "/late.txt");
    const auto r =
        run(kBin + "/wifi-graphslam --no-plots -b " + f.dir + "/bearings.csv --odometry-tum " +
            f.dir + "/late.txt -o " + f.dir + "/gs2");
    EXPECT_EQ(r.rc, 1);
    EXPECT_NE(r.out.find("overlap"), std::string::npos) << r.out;
}

TEST(LocalizationAppsIot, MapsDevicesAndReportsUnknownNames)
{
    const auto& f = fixture();
    const auto r =
        run(kBin + "/wifi-iot-map -q --no-plots -b " + f.dir + "/bearings.csv -t " + f.dir +
            "/truth.txt --sensor-pose 0.1 0 0 0 0 0 --truth " + f.dir + "/aps.yaml -o " + f.dir +
            "/iot");
    ASSERT_EQ(r.rc, 0) << r.out;
    EXPECT_NE(r.out.find("0 true devices not localized"), std::string::npos) << r.out;
    EXPECT_TRUE(mrpt::system::fileExists(f.dir + "/iot/devices.yaml"));
    // A name that no map resolves is an error naming it, not a silently dropped row.
    std::ofstream(f.dir + "/named.csv") << "timestamp,transmitter,aoa_deg\n1700000001,plug,10\n";
    const auto bad =
        run(kBin + "/wifi-iot-map -q -b " + f.dir + "/named.csv -t " + f.dir + "/truth.txt -o " +
            f.dir + "/iot2");
    EXPECT_EQ(bad.rc, 1);
    EXPECT_NE(bad.out.find("'plug'"), std::string::npos) << bad.out;
}
