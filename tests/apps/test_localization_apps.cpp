/* mrpt_wifi — WiFi channel state information for MRPT.  */
// The command-line programs, and the map inside Debian's own pf-localization (LD_PRELOAD).
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/graphs/CNetworkOfPoses.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/RawlogIO.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
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
         {"wifi-pf-localization", "wifi-graphslam", "wifi-iot-map", "wifi-bearings-synth",
          "live-replay"})
    {
        const auto r = run(kBin + "/" + app + " --help");
        EXPECT_EQ(r.rc, 0) << app << ": " << r.out;
        EXPECT_NE(r.out.find("USAGE"), std::string::npos) << app;
    }
    // Both particle filters take a seed (MRPT seeds its generator from the clock), and a seed
    // that is not a number is refused before any work.
    for (const char* app : {"wifi-pf-localization", "wifi-localize"})
    {
        EXPECT_NE(run(kBin + "/" + app + " --help").out.find("--seed"), std::string::npos) << app;
        const auto bad = run(kBin + "/" + app + " --seed many " + kIni);
        EXPECT_NE(bad.rc, 0) << app << ": " << bad.out;
        EXPECT_NE(bad.out.find("seed"), std::string::npos) << app << ": " << bad.out;
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

namespace
{
std::string getenvOr(const char* name, const char* fallback)
{
    const char* v = std::getenv(name);
    return v && *v ? v : fallback;
}

/** Median of errors.csv's position errors from `from_s` seconds on. */
double medianError(const std::string& errorsCsv, double from_s)
{
    std::ifstream f(errorsCsv);
    std::string line;
    std::getline(f, line);  // header
    std::vector<double> e;
    for (double t, v; std::getline(f, line);)
        if (std::sscanf(line.c_str(), "%lf,%lf", &t, &v) == 2 && t >= from_s) e.push_back(v);
    if (e.empty()) return 1e9;
    std::nth_element(e.begin(), e.begin() + long(e.size() / 2), e.end());
    return e[e.size() / 2];
}
}  // namespace

TEST(LocalizationAppsPf, WithoutOdometryTracksAMovingRobot)
{
    // Issue 12.3: a moving robot (0.5 m/s), 4 APs, no odometry at all: the unknown-motion model
    // (constant velocity from the filter's own estimates + a heavy-tailed random walk bounded by
    // --max-speed, the shipped .ini's values) must track it. The issue's target is 1.5x the
    // error with odometry: kidnapped.yaml gives 1.33-1.52x at 30 bearings/AP/s, 1.75-2.04x at
    // 10/s; this world with sharp corners and 5 bearings/AP/s is the hard case (2.0-2.6x).
    // Bearing noise as csi-bearings gives on the simulator (~8 deg, 10 % outliers).
    const auto& f = fixture();
    WorldOptions o;
    o.duration_s = 60, o.aoaStd = o.aodStd = 0.14, o.outliers = 0.1;
    o.seed = std::stoul(getenvOr("PF_SEED", "5"));
    const World w = makeWorld(f.w.aps, o);
    writeBearingCsv(f.dir + "/noisy.csv", w.bearings);
    w.odometry.saveTum(f.dir + "/noisy-odo.txt");
    w.truth.saveTum(f.dir + "/noisy-truth.txt");
    const std::string common = kBin + "/wifi-pf-localization " + kIni +
                               " -q --no-plots -n 3000 -m " + f.dir + "/aps.yaml -b " + f.dir +
                               "/noisy.csv --sensor-pose 0.1 0 0 0 0 0 -g " + f.dir +
                               "/noisy-truth.txt";
    const auto withOdo =
        run(common + " --odometry-tum " + f.dir + "/noisy-odo.txt -o " + f.dir + "/pf-odo");
    ASSERT_EQ(withOdo.rc, 0) << withOdo.out;
    const auto noOdo = run(common + " --max-speed 0.6 -o " + f.dir + "/pf-noodo");
    ASSERT_EQ(noOdo.rc, 0) << noOdo.out;
    EXPECT_NE(
        noOdo.out.find("no odometry (constant velocity + random walk, max speed 0.6 m/s"),
        std::string::npos)
        << noOdo.out;
    // Every AP's bearings are 8° sharp: 3 or more transmitters in every second of the drive.
    EXPECT_TRUE(std::regex_search(
        mrpt_wifi::test::readFile(f.dir + "/pf-noodo/summary.txt"),
        std::regex(
            R"(sharp bearings : 3\+ transmitters with a sharp bearing in 100 % of 6[01] s)")))
        << noOdo.out;
    const double eOdo = medianError(f.dir + "/pf-odo/errors.csv", 15);
    const double eNo = medianError(f.dir + "/pf-noodo/errors.csv", 15);
    std::cout << "median error after 15 s: with odometry " << eOdo << " m, without " << eNo
              << " m\n";
    // Measured on seeds 5-7: 0.19-0.23 m without odometry vs 0.07-0.11 m with it. One Gaussian
    // walk gave 0.27-0.33 m (correlation_time_s = 0.2) and 0.95-1.23 m (0.05: it loses the
    // robot in the corners); "standing still" odometry 2.9 m.
    EXPECT_LT(eNo, 0.3) << noOdo.out;
    EXPECT_LT(eNo, 3.5 * eOdo) << noOdo.out;
    // --seed (default 1): the same input and seed give the same run, estimate for estimate.
    const auto again = run(common + " --max-speed 0.6 -o " + f.dir + "/pf-noodo-again");
    ASSERT_EQ(again.rc, 0) << again.out;
    EXPECT_EQ(
        mrpt_wifi::test::readFile(f.dir + "/pf-noodo/estimate_tum.txt"),
        mrpt_wifi::test::readFile(f.dir + "/pf-noodo-again/estimate_tum.txt"));
    EXPECT_EQ(again.out.find("not reproducible"), std::string::npos) << again.out;
    // Without odometry and without a sane speed the model refuses to run.
    const auto bad = run(common + " --max-speed 0 -o " + f.dir + "/pf-bad");
    EXPECT_EQ(bad.rc, 1);
    EXPECT_NE(bad.out.find("max_speed_mps must be > 0"), std::string::npos) << bad.out;
}

TEST(LocalizationAppsPf, WithoutOdometryUnknownMotionBearingWeightTempersTheBearings)
{
    // [UnknownMotion] bearing_weight multiplies each bearing's log-likelihood while the motion
    // is unknown: the same run as the map's own bearing_weight at that value, another run than
    // the untempered one (the same input and seed).
    const auto& f = fixture();
    const auto iniWith = [&](const std::string& name, const std::string& section, double weight)
    {
        mrpt::config::CConfigFileMemory ini(mrpt::io::file_get_contents(kIni));
        ini.write(section, "bearing_weight", weight);
        std::string text;
        ini.getContent(text);
        const std::string path = f.dir + "/" + name + ".ini";
        std::ofstream(path) << text;
        return path;
    };
    const auto runWith = [&](const std::string& ini, const std::string& out)
    {
        const auto r =
            run(kBin + "/wifi-pf-localization " + ini +
                " -q --no-plots -n 500 --max-speed 0.6 -m " + f.dir + "/aps.yaml -b " + f.dir +
                "/bearings.csv --sensor-pose 0.1 0 0 0 0 0 -o " + f.dir + "/" + out);
        EXPECT_EQ(r.rc, 0) << r.out;
        return std::make_pair(
            r.out, mrpt_wifi::test::readFile(f.dir + "/" + out + "/estimate_tum.txt"));
    };
    const auto motion = runWith(iniWith("motion-half", "UnknownMotion", 0.5), "pf-motion-half");
    const auto map = runWith(
        iniWith("map-half", "MetricMap_wifiBearingMap_00_likelihoodOpts", 0.5), "pf-map-half");
    const auto plain = runWith(kIni, "pf-untempered");
    EXPECT_NE(motion.first.find("bearings weighted 0.5"), std::string::npos) << motion.first;
    ASSERT_FALSE(motion.second.empty());
    EXPECT_EQ(motion.second, map.second);
    EXPECT_NE(motion.second, plain.second);
}

TEST(LocalizationAppsPf, WithoutOdometryWithinOneAndAHalfTimesTheOdometryError)
{
    // Issue 12.3's target on kidnapped.yaml (4 APs, 0.6 m/s): without odometry, the median error
    // after convergence within 1.5x the error with odometry through MRPT's per-step model (the
    // odometry model of that issue; [OdometryMotion] left out). Dense bearings, 30 per second per
    // AP (csi-bearings gives one per frame; this scenario sends 100 frames/s per AP), evaluation
    // seed 81, the first 40 s, the shipped .ini, 2000 particles, --seed 1. Measured: 1.40x
    // (0.065 m vs 0.047 m); the earlier default, one Gaussian walk with a 0.2 s horizon: 1.74x.
    // The shipped odometry model ([OdometryMotion], issue 19) must beat MRPT's: 0.027 m vs
    // 0.048 m, so against it the ratio is 2.4x (1.34x against MRPT's).
    const std::string sim = kBin + "/wifi-sim";
    if (!mrpt::system::fileExists(sim)) GTEST_SKIP() << "wifi-sim not built";
    const std::string share = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";
    const mrpt_wifi::test::TempDir tmp;
    const std::string dir = tmp.path().string(), t = dir + "/truth";
    ASSERT_EQ(
        run(sim + " -q " + share + "/scenarios/kidnapped.yaml /dev/null -d 40 -s 81 -t " + t).rc,
        0);
    const auto synth =
        run(kBin + "/wifi-bearings-synth " + t + "/frames.csv " + t + "/transmitters.yaml " + dir +
            "/k.csv --rx-array " + share + "/arrays/rt-ac86u.yaml -s 81 --rate 30");
    ASSERT_EQ(synth.rc, 0) << synth.out;
    // The shipped .ini without its [OdometryMotion] section: MRPT's model, and the particle
    // filter alone (no [WindowSmoother]), as Debian's pf-localization runs it.
    const std::string mrptModelIni = dir + "/mrpt-odometry-model.ini";
    {
        std::istringstream in(mrpt_wifi::test::readFile(kIni));
        std::ofstream o(mrptModelIni);
        bool skip = false;
        for (std::string line; std::getline(in, line);)
        {
            if (!line.empty() && line[0] == '[')
                skip = line == "[OdometryMotion]" || line == "[WindowSmoother]";
            if (!skip) o << line << "\n";
        }
        o << "[WindowSmoother]\nenabled = false\n";
    }
    const std::string args = " -q --no-plots -n 2000 -m " + t + "/transmitters.yaml -b " + dir +
                             "/k.csv --sensor-pose 0.1 0 0.4 0 0 0 -g " + t +
                             "/trajectory_tum.txt --max-speed 0.6";
    const std::string pf = kBin + "/wifi-pf-localization ";
    const std::string odometry = " --odometry-tum " + t + "/odometry_tum.txt";
    const auto withOdo = run(pf + kIni + args + odometry + " -o " + dir + "/odo");
    ASSERT_EQ(withOdo.rc, 0) << withOdo.out;
    const auto withOdoMrpt = run(pf + mrptModelIni + args + odometry + " -o " + dir + "/odo-mrpt");
    ASSERT_EQ(withOdoMrpt.rc, 0) << withOdoMrpt.out;
    const auto noOdo = run(pf + kIni + args + " -o " + dir + "/no-odo");
    ASSERT_EQ(noOdo.rc, 0) << noOdo.out;
    const double eOdo = medianError(dir + "/odo/errors.csv", 5);
    const double eOdoMrpt = medianError(dir + "/odo-mrpt/errors.csv", 5);
    const double eNo = medianError(dir + "/no-odo/errors.csv", 5);
    std::cout << "median error after 5 s: with odometry " << eOdo << " m (MRPT's model " << eOdoMrpt
              << " m), without " << eNo << " m (" << eNo / eOdoMrpt << "x, " << eNo / eOdo
              << "x)\n";
    EXPECT_LE(eNo, 1.5 * eOdoMrpt) << noOdo.out;
    EXPECT_LT(eOdoMrpt, 0.1) << withOdoMrpt.out;
    EXPECT_LT(eOdo, 0.8 * eOdoMrpt) << withOdo.out;
}

namespace
{
/** The robot is kidnapped 20 s into a drive: from then on it is where the room turned by 180°
 *  about its centre puts it (the same motion in its own frame, so its odometry notices
 *  nothing). Returns the input folder: bearings.csv, odometry.txt, truth.txt. */
std::string kidnappedMidRun(const std::string& dir)
{
    const auto& f = fixture();
    WorldOptions o;
    o.duration_s = 50, o.rate_Hz = 10, o.seed = 11;
    const World a = makeWorld(f.w.aps, o);
    for (auto& p : o.loop) p = {10 - p.x, 5 - p.y};
    const World b = makeWorld(f.w.aps, o);
    const double tKidnap = a.truth.t.front() + 20;
    std::vector<BearingRecord> bearings;
    for (const auto& r : a.bearings)
        if (r.t < tKidnap) bearings.push_back(r);
    for (const auto& r : b.bearings)
        if (r.t >= tKidnap) bearings.push_back(r);
    Trajectory2D truth;
    for (size_t i = 0; i < a.truth.size(); ++i)
        truth.push_back(a.truth.t[i], a.truth.t[i] < tKidnap ? a.truth.poses[i] : b.truth.poses[i]);
    mrpt::system::createDirectory(dir);
    writeBearingCsv(dir + "/bearings.csv", bearings);
    a.odometry.saveTum(dir + "/odometry.txt");
    truth.saveTum(dir + "/truth.txt");
    return dir;
}

double medianErrorBetween(const std::string& errorsCsv, double from_s, double to_s)
{
    std::ifstream f(errorsCsv);
    std::vector<double> e;
    std::string line;
    for (double t, v; std::getline(f, line);)
        if (std::sscanf(line.c_str(), "%lf,%lf", &t, &v) == 2 && t >= from_s && t <= to_s)
            e.push_back(v);
    if (e.empty()) return 1e9;
    std::nth_element(e.begin(), e.begin() + long(e.size() / 2), e.end());
    return e[e.size() / 2];
}
}  // namespace

TEST(LocalizationAppsPf, FindsTheRobotAgainAfterAKidnappingMidRun)
{
    // Issue 19.2: a filter that has converged and then loses the robot must recover when the
    // bearings disagree with its estimate ([ParticleRecovery] re-seeds particles over the map's
    // area), with and without odometry; and it never leaves the room. Without recovery
    // (rate_hz = 0) and without the motion models' heavy tails (wide_fraction = 0,
    // jump_rate_hz = 0; the jumps of the shipped [OdometryMotion] alone also find the robot
    // again, partly) the run with odometry stays lost (5.0 m): the test can fail.
    const mrpt_wifi::test::TempDir tmp;
    const std::string dir = kidnappedMidRun(tmp.path().string() + "/in");
    const std::string noRecovery = tmp.path().string() + "/no-recovery.ini";
    {
        std::ifstream in(kIni);
        std::ofstream out(noRecovery);
        for (std::string l; std::getline(in, l);)
            out << (l.rfind("rate_hz", 0) == 0         ? "rate_hz = 0"
                    : l.rfind("wide_fraction", 0) == 0 ? "wide_fraction = 0"
                    : l.rfind("jump_rate_hz", 0) == 0  ? "jump_rate_hz = 0"
                                                       : l)
                << "\n";
    }
    const auto& f = fixture();
    const std::vector<std::string> motions = {
        "--odometry-tum " + dir + "/odometry.txt", "--max-speed 0.6"};
    for (const auto& motion : motions)
    {
        const auto runWith = [&](const std::string& ini, const std::string& out)
        {
            const auto r =
                run(kBin + "/wifi-pf-localization " + ini + " -q --no-plots -n 3000 -m " + f.dir +
                    "/aps.yaml -b " + dir + "/bearings.csv --sensor-pose 0.1 0 0 0 0 0 -g " + dir +
                    "/truth.txt " + motion + " -o " + out);
            EXPECT_EQ(r.rc, 0) << r.out;
            return r;
        };
        const std::string out = tmp.path().string() + "/rec",
                          outNo = tmp.path().string() + "/norec";
        const auto withRecovery = runWith(kIni, out);
        const auto without = runWith(noRecovery, outNo);
        // Before the kidnapping both track the robot; from 10 s after it only the one that
        // recovers does (the kidnapping is at 20 s; the run ends at 50 s).
        const double before = medianErrorBetween(out + "/errors.csv", 10, 20);
        const double after = medianErrorBetween(out + "/errors.csv", 30, 50);
        const double afterNo = medianErrorBetween(outNo + "/errors.csv", 30, 50);
        std::cout << motion.substr(0, 14) << ": median error before the kidnapping " << before
                  << " m, 10-30 s after it " << after << " m (without recovery " << afterNo
                  << " m)\n";
        EXPECT_LT(before, 0.3) << withRecovery.out;
        EXPECT_LT(after, 0.3) << withRecovery.out;
        // With odometry and no jumps nothing else moves the particles that far.
        if (motion.rfind("--odometry-tum", 0) == 0)
        {
            EXPECT_GT(afterNo, 1.0) << without.out;
        }
        EXPECT_NE(withRecovery.out.find(" 0 estimates outside it"), std::string::npos)
            << withRecovery.out;
        const auto est = Trajectory2D::fromTumFile(out + "/estimate_tum.txt");
        for (const auto& p : est.poses)
            ASSERT_TRUE(p.x >= 0 && p.x <= 10 && p.y >= 0 && p.y <= 5) << p.asString();
    }
}

TEST(LocalizationAppsPf, TimeToConvergeCountsFromTheKidnapping)
{
    // Issue 12.5: the reported time is the one errors.csv shows (seconds since the kidnapping
    // moment, --skip), with its definition: first estimate after which the error stays below
    // the threshold for the hold time.
    const auto& f = fixture();
    const double thr = 0.15, hold = 3;
    const auto r =
        run(kBin + "/wifi-pf-localization " + kIni + " -q --no-plots -n 1500 -m " + f.dir +
            "/aps.yaml -b " + f.dir + "/bearings.csv --odometry-tum " + f.dir +
            "/odometry.txt --sensor-pose 0.1 0 0 0 0 0 -g " + f.dir +
            "/truth.txt --skip 10 --converged-threshold 0.15 --converged-hold 3 -o " + f.dir +
            "/pf-kidnap");
    ASSERT_EQ(r.rc, 0) << r.out;
    const auto p = r.out.find("converged after: ");
    ASSERT_NE(p, std::string::npos) << r.out;
    double reported = -1;
    unsigned steps = 0;
    ASSERT_EQ(
        std::sscanf(
            r.out.c_str() + p, "converged after: %lf s from the kidnapping (%u filter steps",
            &reported, &steps),
        2)
        << r.out.substr(p, 200);
    std::ifstream ef(f.dir + "/pf-kidnap/errors.csv");
    std::string line;
    std::vector<double> t, e;
    while (std::getline(ef, line))
        if (double a, b; std::sscanf(line.c_str(), "%lf,%lf", &a, &b) == 2)
            t.push_back(a), e.push_back(b);
    ASSERT_GT(t.size(), 50u);
    EXPECT_GE(t.front(), 0.0) << "errors.csv counts from the kidnapping moment";
    EXPECT_LT(t.front(), 0.5);
    ASSERT_GE(steps, 1u);
    ASSERT_LE(steps, t.size());
    EXPECT_NEAR(reported, t[steps - 1], 0.006);
    // Below the threshold from there on for the hold time, and not at the estimate before.
    for (size_t i = steps - 1; i < t.size() && t[i] - reported < hold; ++i)
        EXPECT_LT(e[i], thr) << "t = " << t[i];
    if (steps > 1)
    {
        bool brokeOut = false;
        for (size_t i = 0; i + 1 < steps; ++i) brokeOut |= e[i] >= thr;
        EXPECT_TRUE(brokeOut) << "an earlier start would have qualified";
    }
}

TEST(LocalizationAppsLiveReplay, SameInputSameRunAndALateStartNeverSeesTheBearingsBefore)
{
    // live-replay: wifi-localize's filter without the clock. What it is for: a run that can be
    // repeated exactly, with the start and the bearings per step set on the command line.
    const auto& f = fixture();
    const std::string common = kBin + "/live-replay " + kIni + " -q -n 1000 -m " + f.dir +
                               "/aps.yaml -b " + f.dir +
                               "/bearings.csv --sensor-pose 0.1 0 0 0 0 0 --seed 3";
    const auto first = run(common + " --bearings-per-step 2 -o " + f.dir + "/replay");
    ASSERT_EQ(first.rc, 0) << first.out;
    const auto again = run(common + " --bearings-per-step 2 -o " + f.dir + "/replay-again");
    ASSERT_EQ(again.rc, 0) << again.out;
    const std::string estimate = mrpt_wifi::test::readFile(f.dir + "/replay/estimate_tum.txt");
    EXPECT_FALSE(estimate.empty());
    EXPECT_EQ(estimate, mrpt_wifi::test::readFile(f.dir + "/replay-again/estimate_tum.txt"));
    EXPECT_NE(
        first.out.find(std::to_string(f.w.bearings.size()) + " bearings from 0 s"),
        std::string::npos)
        << first.out;

    // It is the live filter, and it finds the robot: median error after 20 s, true poses.
    const auto est = Trajectory2D::fromTumFile(f.dir + "/replay/estimate_tum.txt");
    std::vector<double> errors;
    for (size_t i = 0; i < est.size(); ++i)
        if (mrpt::math::TPose2D truth;
            est.t[i] >= est.t.front() + 20 && f.w.truth.interpolate(est.t[i], truth))
            errors.push_back(std::hypot(est.poses[i].x - truth.x, est.poses[i].y - truth.y));
    ASSERT_FALSE(errors.empty());
    std::nth_element(errors.begin(), errors.begin() + long(errors.size() / 2), errors.end());
    EXPECT_LT(errors[errors.size() / 2], 0.5);

    // A late start: nothing before it reaches the filter.
    const auto late = run(common + " --skip 10 -o " + f.dir + "/replay-late");
    ASSERT_EQ(late.rc, 0) << late.out;
    const auto lateEst = Trajectory2D::fromTumFile(f.dir + "/replay-late/estimate_tum.txt");
    ASSERT_FALSE(lateEst.empty());
    double firstBearing = f.w.bearings.front().t;
    for (const auto& b : f.w.bearings) firstBearing = std::min(firstBearing, b.t);
    EXPECT_GE(lateEst.t.front(), firstBearing + 10);
    const size_t before = size_t(std::count_if(
        f.w.bearings.begin(), f.w.bearings.end(),
        [&](const BearingRecord& b) { return b.t < firstBearing + 10; }));
    EXPECT_NE(
        late.out.find(std::to_string(f.w.bearings.size() - before) + " bearings from 10 s"),
        std::string::npos)
        << late.out;
    // One bearing per step (the default) is one step per bearing, as offline.
    EXPECT_NE(
        late.out.find(
            std::to_string(f.w.bearings.size() - before) + " filter steps, queued 1 at a time"),
        std::string::npos)
        << late.out;

    const auto bad = run(common + " --bearings-per-step 0 -o " + f.dir + "/replay-bad");
    EXPECT_EQ(bad.rc, 1);
    EXPECT_NE(bad.out.find("--bearings-per-step must be >= 1"), std::string::npos) << bad.out;
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

TEST(LocalizationAppsPf, BearingsTheMapDoesNotWeighAreAnError)
{
    // Every bearing wider than the map's max_std_deg: the filter would run to the end and
    // report its initial distribution. Refused before it runs, naming the keys.
    const auto& f = fixture();
    const std::string ini = f.dir + "/narrow.ini";
    {
        std::ifstream in(kIni);
        std::ofstream out(ini);
        bool replaced = false;
        for (std::string line; std::getline(in, line);)
        {
            if (line.rfind("max_std_deg", 0) == 0) line = "max_std_deg = 0.0001", replaced = true;
            out << line << "\n";
        }
        ASSERT_TRUE(replaced) << kIni;
    }
    const auto r =
        run(kBin + "/wifi-pf-localization " + ini + " -q --no-plots -n 100 -m " + f.dir +
            "/aps.yaml -b " + f.dir + "/bearings.csv --odometry-tum " + f.dir +
            "/odometry.txt --sensor-pose 0.1 0 0 0 0 0 -o " + f.dir + "/pf-narrow");
    EXPECT_EQ(r.rc, 1) << r.out;
    EXPECT_NE(r.out.find("has an angle the map weighs"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("max_std_deg = 0.0"), std::string::npos) << r.out;
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

namespace
{
/** "median ATE reduction: X %" of a wifi-graphslam summary; NaN when absent. */
double ateReduction(const std::string& out)
{
    const std::string key = "median ATE reduction:";
    const size_t p = out.find(key);
    return p == std::string::npos ? std::nan("") : std::atof(out.c_str() + p + key.size());
}

/** Issue 12.1's reproducer: loop.yaml without antenna jumps -> wifi-sim -> truth calibration ->
 *  csi-bearings --algo aoa_only -> wifi-graphslam with the known AP map vs estimated APs. The
 *  known map must never make the result worse (>= estimated - 5 points). The issue measured
 *  -494 % vs -51 % on seed 41: the calibration files were the scenario's seed's (another boot's
 *  receiver offsets; AoA median 21 deg instead of 1 deg), see bearing-accuracy --seed. */
void knownVsEstimatedApsOnLoop(unsigned seed, bool alsoWrongCalibration)
{
    const std::string sim = kBin + "/wifi-sim", cb = kBin + "/csi-bearings",
                      ba = kBin + "/bearing-accuracy";
    for (const auto& p : {sim, cb, ba})
        if (!mrpt::system::fileExists(p)) GTEST_SKIP() << p << " not built";
    const std::string d = mrpt_wifi::test::tempPath("_loop" + std::to_string(seed));
    ASSERT_TRUE(mrpt::system::createDirectory(d));
    const std::string share = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";
    {
        std::ifstream in(share + "/scenarios/loop.yaml");
        ASSERT_TRUE(in.good());
        std::stringstream ss;
        ss << in.rdbuf();
        std::string y = ss.str();
        const auto replaceAll = [&](const std::string& a, const std::string& b)
        {
            for (size_t p = y.find(a); p != std::string::npos; p = y.find(a, p + b.size()))
                y.replace(p, a.size(), b);
        };
        replaceAll("antenna_jumps: {enabled: true", "antenna_jumps: {enabled: false");
        replaceAll("../arrays/", share + "/arrays/");
        ASSERT_NE(y.find("antenna_jumps: {enabled: false"), std::string::npos);
        std::ofstream(d + "/loop.yaml") << y;
    }
    const std::string s = std::to_string(seed);
    auto r = run(
        sim + " -q " + d + "/loop.yaml " + d + "/sim.rawlog -d 60 -s " + s + " -t " + d + "/truth");
    ASSERT_EQ(r.rc, 0) << r.out;
    r = run(ba + " --truth-calibration " + d + "/loop.yaml " + d + "/calib --seed " + s);
    ASSERT_EQ(r.rc, 0) << r.out;
    r =
        run(cb + " -q " + d + "/sim.rawlog " + d + "/b.rawlog --algo aoa_only --stride 2 --calib " +
            d + "/calib");
    ASSERT_EQ(r.rc, 0) << r.out;
    const std::string gs = kBin + "/wifi-graphslam --no-plots -r " + d + "/b.rawlog --aps " + d +
                           "/truth/transmitters.yaml --no-aod --sensor-pose 0.1 0 0.4 0 0 0 -g " +
                           d + "/truth/trajectory_tum.txt";
    const auto known = run(gs + " -o " + d + "/known");
    ASSERT_EQ(known.rc, 0) << known.out;
    const auto est = run(gs + " --estimate-aps -o " + d + "/est");
    ASSERT_EQ(est.rc, 0) << est.out;
    const double k = ateReduction(known.out), e = ateReduction(est.out);
    std::cout << "seed " << seed << ": median ATE reduction, known APs " << k
              << " %, estimated APs " << e << " %\n";
    // Measured (60 s, stride 2): seed 41 78 % / 43 %, seed 42 83 % / 56 %.
    EXPECT_GE(k, e - 5) << known.out << est.out;
    EXPECT_GT(k, 50) << known.out;
    EXPECT_EQ(known.out.find("WARNING"), std::string::npos) << known.out;
    // With estimated APs the map's scale is the odometry's: said, and the ATE without it shown.
    EXPECT_NE(est.out.find("scale     : with estimated APs"), std::string::npos) << est.out;
    EXPECT_EQ(known.out.find("scale     :"), std::string::npos) << known.out;
    const std::string scaleFreeLabel = "median ATE reduction without the scale: ";
    const auto scaleFree = est.out.find(scaleFreeLabel);
    ASSERT_NE(scaleFree, std::string::npos) << est.out;
    EXPECT_GE(std::stod(est.out.substr(scaleFree + scaleFreeLabel.size())), e - 5) << est.out;
    if (!alsoWrongCalibration) return;
    // The issue's trap: the scenario's own seed's calibration on a -s N recording. The
    // bearings are biased by ~20 deg; wifi-graphslam must say so instead of a silent result.
    r = run(ba + " --truth-calibration " + d + "/loop.yaml " + d + "/calib-other");
    ASSERT_EQ(r.rc, 0) << r.out;
    r =
        run(cb + " -q " + d + "/sim.rawlog " + d + "/b-other.rawlog --algo aoa_only --stride 8 " +
            "--calib " + d + "/calib-other");
    ASSERT_EQ(r.rc, 0) << r.out;
    const auto other =
        run(kBin + "/wifi-graphslam --no-plots -r " + d + "/b-other.rawlog --aps " + d +
            "/truth/transmitters.yaml --no-aod --sensor-pose 0.1 0 0.4 0 0 0 -o " + d + "/other");
    ASSERT_EQ(other.rc, 0) << other.out;
    EXPECT_NE(other.out.find("WARNING   : the bearings disagree"), std::string::npos) << other.out;
}
}  // namespace

TEST(LocalizationAppsGraphSlam, KnownApsAoaOnlyPipelineSeed41)
{
    knownVsEstimatedApsOnLoop(41, true);
}
TEST(LocalizationAppsGraphSlam, KnownApsAoaOnlyPipelineSeed42)
{
    knownVsEstimatedApsOnLoop(42, false);
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

TEST(LocalizationAppsIot, DevicesFromDriftingOdometryJointly)
{
    // Issue 12.2: with the robot's drifting odometry (not a trusted trajectory) devices and
    // trajectory are estimated jointly; the reported sigma must cover the error.
    const auto& f = fixture();
    WorldOptions o;
    o.duration_s = 60, o.aod = false;
    o.odoScaleError = 0.02, o.odoYawDrift = 0.03;  // ~1 m of drift over the drive
    o.seed = 9;
    const World w = makeWorld(f.w.aps, o);
    writeBearingCsv(f.dir + "/iot-b.csv", w.bearings);
    w.odometry.saveTum(f.dir + "/iot-odo.txt");
    const auto& s = w.truth.poses.front();
    const std::string common = kBin + "/wifi-iot-map -q --no-plots -b " + f.dir +
                               "/iot-b.csv --sensor-pose 0.1 0 0 0 0 0 --truth " + f.dir +
                               "/aps.yaml ";
    const auto r =
        run(common + "--odometry-tum " + f.dir + "/iot-odo.txt --initial-pose " +
            std::to_string(s.x) + " " + std::to_string(s.y) + " " +
            std::to_string(mrpt::RAD2DEG(s.phi)) + " -o " + f.dir + "/iot-joint");
    ASSERT_EQ(r.rc, 0) << r.out;
    EXPECT_NE(r.out.find("estimated jointly from odometry"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("0 true devices not localized"), std::string::npos) << r.out;
    // Errors and sigmas from the summary lines.
    std::istringstream is(r.out);
    std::vector<double> errs;
    size_t covered = 0;
    for (std::string line; std::getline(is, line);)
    {
        double sx, sy, e;
        const auto ps = line.find("sigma=("), pe = line.find("error=");
        if (ps == std::string::npos || pe == std::string::npos) continue;
        ASSERT_EQ(std::sscanf(line.c_str() + ps, "sigma=(%lf, %lf)", &sx, &sy), 2) << line;
        ASSERT_EQ(std::sscanf(line.c_str() + pe, "error=%lf", &e), 1) << line;
        errs.push_back(e);
        covered += e <= 2 * std::hypot(sx, sy);
    }
    ASSERT_EQ(errs.size(), 4u) << r.out;
    std::sort(errs.begin(), errs.end());
    EXPECT_LE(0.5 * (errs[1] + errs[2]), 0.5) << r.out;
    EXPECT_GE(covered, 2u) << r.out;  // the issue: >= 2 of 3 devices within 2 sigma
    // Issue 19.3: every device inside its 95 % ellipse (the summary checks it against --truth).
    EXPECT_NE(r.out.find("inside their 95 % ellipse: 4 of 4 true devices"), std::string::npos)
        << r.out;
    EXPECT_TRUE(mrpt::system::fileExists(f.dir + "/iot-joint/trajectory_tum.txt"));
    // Trusting the same odometry as the trajectory is what the joint estimate improves on.
    const auto trusted = run(common + "-t " + f.dir + "/iot-odo.txt -o " + f.dir + "/iot-odo");
    ASSERT_EQ(trusted.rc, 0) << trusted.out;
    EXPECT_EQ(
        run(common + "-t " + f.dir + "/iot-odo.txt --odometry-tum " + f.dir + "/iot-odo.txt -o " +
            f.dir + "/iot-bad")
            .rc,
        1);
}

TEST(LocalizationAppsIot, TrustedOdometrySigmaCoversItsDrift)
{
    // Issue 11.3 / 12.2: the live device map (wifi-localize map_devices) is
    // `wifi-iot-map --trust-odometry`: the odometry is taken as the trajectory, so the devices'
    // sigma must include its drift (--odometry-drift), or the 95 % ellipses miss the devices
    // (4 of 12 covered before). iot.yaml, odometry started at the true pose, seeds 61-63.
    const std::string sim = kBin + "/wifi-sim";
    if (!mrpt::system::fileExists(sim)) GTEST_SKIP() << "wifi-sim not built";
    const std::string share = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";
    const std::string d = mrpt_wifi::test::tempPath("_iotdrift");
    ASSERT_TRUE(mrpt::system::createDirectory(d));
    size_t devices = 0, covered = 0;
    std::vector<double> errs, sigmas;
    for (const std::string seed : {"61", "62", "63"})
    {
        const std::string t = d + "/t" + seed;
        ASSERT_EQ(
            run(sim + " -q " + share + "/scenarios/iot.yaml " + d + "/s.rawlog -d 90 -s " + seed +
                " -t " + t)
                .rc,
            0);
        ASSERT_EQ(
            run(kBin + "/wifi-bearings-synth " + t + "/frames.csv " + t + "/transmitters.yaml " +
                d + "/b.csv --no-aod --rx-array " + share + "/arrays/rt-ac86u.yaml -s " + seed)
                .rc,
            0);
        const auto r =
            run(kBin + "/wifi-iot-map -q --no-plots -b " + d + "/b.csv --odometry-tum " + t +
                "/odometry_tum.txt --trust-odometry --initial-pose \"2 1.5 0\" --sensor-pose "
                "0.1 0 0.4 0 0 0 --truth " +
                t + "/transmitters.yaml -o " + d + "/out" + seed);
        ASSERT_EQ(r.rc, 0) << r.out;
        EXPECT_NE(r.out.find("trajectory poses (trusted)"), std::string::npos) << r.out;
        std::istringstream is(r.out);
        for (std::string line; std::getline(is, line);)
        {
            double sx, sy, e;
            const auto ps = line.find("sigma=("), pe = line.find("error=");
            if (ps == std::string::npos || pe == std::string::npos) continue;
            ASSERT_EQ(std::sscanf(line.c_str() + ps, "sigma=(%lf, %lf)", &sx, &sy), 2) << line;
            ASSERT_EQ(std::sscanf(line.c_str() + pe, "error=%lf", &e), 1) << line;
            ++devices;
            errs.push_back(e);
            sigmas.push_back(std::max(sx, sy));
            // Inside the 95 % ellipse (chi-square, 2 dof: 5.99) of the (near-isotropic) sigma.
            covered += e * e <= 5.99 * 0.5 * (sx * sx + sy * sy);
        }
    }
    ASSERT_EQ(devices, 9u);
    std::sort(errs.begin(), errs.end());
    std::sort(sigmas.begin(), sigmas.end());
    std::cout << covered << " of " << devices << " devices inside their 95 % ellipse; median "
              << "error " << errs[4] << " m, median sigma " << sigmas[4] << " m\n";
    // Measured: 9/9 covered, median error 0.09 m, sigma 0.11-0.19 m (without the drift term:
    // sigma 0.05-0.09 m, the 0.16 m error of seed 61's camera outside).
    EXPECT_GE(covered, 8u);
    EXPECT_LE(errs[4], 0.2);
    EXPECT_LE(sigmas.back(), 0.3);  // honest, not huge: the same order as the errors
}

TEST(LocalizationAppsCsv, CsiBearingsLeavesUnmeasuredCellsEmpty)
{
    // Issue 12.4: `csi-bearings --csv` must not write 0.000 where nothing was measured, and a
    // CSV that does carry angles next to a 0 flag makes the apps warn.
    const std::string sim = kBin + "/wifi-sim", cb = kBin + "/csi-bearings";
    if (!mrpt::system::fileExists(sim) || !mrpt::system::fileExists(cb))
        GTEST_SKIP() << "wifi-sim / csi-bearings not built";
    const auto& f = fixture();
    const std::string scen = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/scenarios/bearing.yaml";
    ASSERT_EQ(run(sim + " -q " + scen + " " + f.dir + "/csi.rawlog -d 1 -s 4").rc, 0);
    const auto r =
        run(cb + " " + f.dir + "/csi.rawlog " + f.dir + "/csi-b.rawlog --algo fft -q --csv " +
            f.dir + "/csi-b.csv");
    ASSERT_EQ(r.rc, 0) << r.out;
    std::ifstream in(f.dir + "/csi-b.csv");
    std::string line;
    ASSERT_TRUE(std::getline(in, line));
    std::vector<std::string> head;
    {
        std::stringstream ss(line);
        for (std::string c; std::getline(ss, c, ',');) head.push_back(c);
    }
    const auto col = [&](const std::string& name)
    { return size_t(std::find(head.begin(), head.end(), name) - head.begin()); };
    const size_t hasAod = col("has_aod"), aod = col("aod_deg"), amb = col("aoa_ambiguous"),
                 mir = col("aoa_mirror_deg");
    ASSERT_LT(std::max({hasAod, aod, amb, mir}), head.size()) << line;
    size_t rows = 0, noAod = 0;
    while (std::getline(in, line))
    {
        std::vector<std::string> c;
        std::stringstream ss(line);
        for (std::string v; std::getline(ss, v, ',');) c.push_back(v);
        c.resize(head.size());
        ++rows;
        if (c[hasAod] == "0")
        {
            ++noAod;
            EXPECT_TRUE(c[aod].empty()) << line;
        }
        if (c[amb] == "0")
        {
            EXPECT_TRUE(c[mir].empty()) << line;
        }
    }
    EXPECT_GT(rows, 10u);
    InputWarnings w;
    readBearingCsv(f.dir + "/csi-b.csv", {}, &w);
    EXPECT_EQ(w.flaggedOffAngles, 0u);
    std::cout << rows << " rows, " << noAod << " without AoD\n";

    // An old-style CSV (0.000 in the cells of has_aod = 0): every reader warns.
    std::ofstream(f.dir + "/old.csv")
        << "timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_ambiguous,aoa_mirror_deg,has_aod,"
           "aod_deg,aod_std_deg,aod_mirror_deg\n"
        << "1700000001.0,02:00:00:00:0a:01,10,3,0,0.000,0,0.000,0.000,0.000\n";
    const auto gs =
        run(kBin + "/wifi-iot-map -q --no-plots -b " + f.dir + "/old.csv -t " + f.dir +
            "/truth.txt -o " + f.dir + "/old-iot");
    EXPECT_NE(gs.out.find("has_aoa/has_aod flag is 0"), std::string::npos) << gs.out;
    const auto pf =
        run(kBin + "/wifi-pf-localization " + kIni + " -q --no-plots -n 100 -m " + f.dir +
            "/aps.yaml -b " + f.dir + "/old.csv -o " + f.dir + "/old-pf");
    EXPECT_NE(pf.out.find("has_aoa/has_aod flag is 0"), std::string::npos) << pf.out;
    const auto sl =
        run(kBin + "/wifi-graphslam --no-plots -b " + f.dir + "/old.csv --odometry-tum " + f.dir +
            "/odometry.txt -o " + f.dir + "/old-gs");
    EXPECT_NE(sl.out.find("has_aoa/has_aod flag is 0"), std::string::npos) << sl.out;
}
